"""Compiled (numba) entry times of the swarm engines' open vehicle x target pairs into the
confirmation disc (mdm_montecarlo.engines.swarm_sensors.confirm).

A step of a swarm engine leaves a few dozen pairs to solve; ``mdm_core.world.first_entry_time``
solved them with a dozen numpy passes whose per-call cost was most of the confirmation's time.
Here each pair is one pass of the same arithmetic in the same order (reach bound, then the
closed form and boundary crossing of entry_kernel.disc_entry), so the times are bit-identical
(tests/montecarlo/test_pair_entry.py compares the two on random pairs).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled
from mdm_core.world.sensors import REACH_SLACK
from mdm_montecarlo.kernels.entry_kernel import disc_entry

FloatArray = NDArray[np.float64]


@compiled
def pair_entry_times(
    start: FloatArray,
    velocity: FloatArray,
    duration: float,
    target_start: FloatArray,
    target_velocity: FloatArray,
    radius: float,
    not_before: FloatArray,
) -> FloatArray:
    """``first_entry_time`` of pair q: vehicle ``start[q]`` (pairs, 2) moving at
    ``velocity[q]`` and target ``target_start[q]`` at ``target_velocity[q]``, both for
    ``duration`` s, disc ``radius``, not before ``not_before[q]``; every pair eligible and one
    target per pair. The targets' speed bound is the fastest of the pairs' targets, as
    first_entry_time computes it when not given one. inf where the disc is not reached."""
    pairs = len(start)
    top = 0.0
    for q in range(pairs):
        for a in range(2):
            top = max(top, target_velocity[q, a] * target_velocity[q, a])
    target_speed = math.sqrt(top * 2.0)
    out = np.full(pairs, np.inf)
    for q in range(pairs):
        north = start[q, 0] - target_start[q, 0]
        east = start[q, 1] - target_start[q, 1]
        dist2 = north * north + east * east
        lo = max(not_before[q], 0.0)
        vx, vy = velocity[q, 0], velocity[q, 1]
        reach = radius + (math.sqrt(vx * vx + vy * vy) + target_speed) * duration + REACH_SLACK
        if not (dist2 <= reach * reach and lo <= duration):
            continue
        rvx = vx - target_velocity[q, 0]
        rvy = vy - target_velocity[q, 1]
        out[q] = disc_entry(north, east, rvx, rvy, dist2 - radius * radius, lo, duration)
    return out
