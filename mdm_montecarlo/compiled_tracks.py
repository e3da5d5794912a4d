"""The dynamic targets' paths for the batch engines, grown by one compiled loop (numba).

``TargetTracks._grow`` draws a chunk of displacements, then walks them (a running sum, the
fold into the area), writes the segments' start nodes and velocities and finds the top speed:
about a dozen numpy passes over (runs, chunk, targets, 2) arrays, each a fresh temporary, which
made the tracks about a sixth of the MDM rows' time (docs/model.md, "Speed of reproduce"). Here
the displacements are drawn by the same numpy call, and one loop per run and target does the
rest with the numpy version's operations in its order: the same paths bit for bit
(tests/montecarlo/test_compiled_tracks.py). The emulator and the companion keep TargetTracks.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled
from mdm_core.world import Scenario, TargetTracks
from mdm_core.world.targets import CHUNK_NODES
from mdm_montecarlo.compiled_waypoints import clip

FloatArray = NDArray[np.float64]

FREE, BOUNCE, REFLECT, CLAMP = range(4)
_RULES = {"free": FREE, "bounce": BOUNCE, "reflect": REFLECT, "clamp": CLAMP}


class CompiledTracks(TargetTracks):
    """TargetTracks whose walk and segment writes run compiled; the draws are numpy's."""

    def _grow(self) -> None:
        assert self.walk is not None
        increments = self._increments()
        end = self._filled + CHUNK_NODES
        if end > self._starts.shape[1]:
            self._starts = self._resized(self._starts, end)
            self._velocity = self._resized(self._velocity, end)
        speed2 = _append(
            increments,
            self._last,
            self._free,
            self._starts,
            self._velocity,
            self._filled,
            _RULES[self.walk.boundary],
            self.area.size,
            self.grid_dt,
        )
        self._max_speed = max(self._max_speed, float(np.sqrt(speed2)))
        self._filled = end


def compiled_tracks(
    scenario: Scenario, n_runs: int, rng: np.random.Generator, horizon: float
) -> TargetTracks:
    """Scenario.tracks(n_runs, rng, horizon), grown by the compiled loop."""
    return CompiledTracks(
        scenario.targets, scenario.area, n_runs, rng, scenario.walk, scenario.grid_dt, horizon
    )


@compiled
def _fold(x: float, size: float) -> float:
    """Area.fold(..., 'reflect') of one coordinate."""
    period = 2.0 * size
    folded = x - math.floor(x / period) * period
    return min(folded, period - folded)


@compiled
def _append(
    increments: FloatArray,
    last: FloatArray,
    free: FloatArray,
    starts: FloatArray,
    velocity: FloatArray,
    filled: int,
    rule: int,
    size: FloatArray,
    grid_dt: float,
) -> float:
    """Walk the chunk of ``increments`` from the ``last`` nodes (``free``: the unfolded
    path's end, for bounce), write segments ``filled`` onwards into ``starts`` and
    ``velocity``, update ``last`` and ``free`` in place; returns the top squared speed."""
    runs, chunk, m, axes = increments.shape
    top = 0.0
    for r in range(runs):
        for j in range(m):
            for c in range(chunk):
                k = filled + c
                for a in range(2):
                    step = increments[r, c, j, a if axes == 2 else 0]
                    start = last[r, j, a]
                    if rule == FREE:
                        node = start + step
                    elif rule == BOUNCE:
                        free[r, j, a] = free[r, j, a] + step
                        node = _fold(free[r, j, a], size[a])
                    else:
                        node = start + step
                        if node < 0.0 or node > size[a]:
                            node = _fold(node, size[a]) if rule == REFLECT else clip(node, size[a])
                    starts[r, k, j, a] = start
                    velocity[r, k, j, a] = (node - start) / grid_dt
                    last[r, j, a] = node
                vx = velocity[r, k, j, 0]
                vy = velocity[r, k, j, 1]
                top = max(top, vx * vx + vy * vy)
    return top
