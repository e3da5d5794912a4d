"""The policy of the batch engine, with its memory check compiled (numba).

``SearchPolicy.memory_distance2`` gathers every (lane, remembered slot) pair into a
(pairs, targets) temporary and reduces it per lane: about a tenth of the engine's time over
thousands of lanes (docs/model.md, "Speed of reproduce"). Here one loop per lane does the same
subtractions, squares and sums and keeps the minimum (exact, so the order of the slots does not
matter): bit-identical answers (tests/montecarlo/test_compiled_memory.py). The live companion
keeps the numpy policy (a batch of one; no compiler at start-up).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled
from mdm_core.search import SearchPolicy
from mdm_core.search.policy import PolicyState

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


@compiled
def _memory_distance2(
    memory: FloatArray, counts: IntArray, lanes: IntArray, positions: FloatArray
) -> FloatArray:
    n, m = positions.shape[0], positions.shape[1]
    out = np.full((n, m), np.inf)
    for i in range(n):
        lane = lanes[i]
        for j in range(m):
            best = np.inf
            for slot in range(counts[lane]):
                north = positions[i, j, 0] - memory[lane, slot, 0]
                east = positions[i, j, 1] - memory[lane, slot, 1]
                d2 = north * north + east * east
                if math.isnan(d2):  # a NaN position stays NaN, as in numpy's minimum
                    best = d2
                    break
                best = min(best, d2)
            out[i, j] = best
    return out


class CompiledMemoryPolicy(SearchPolicy):
    """SearchPolicy whose memory check runs compiled; every other step is the numpy one."""

    def memory_distance2(
        self, state: PolicyState, lanes: IntArray, positions: FloatArray
    ) -> FloatArray:
        return np.asarray(_memory_distance2(state.memory, state.memory_count, lanes, positions))
