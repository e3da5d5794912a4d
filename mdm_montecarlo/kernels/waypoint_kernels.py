"""Compiled (numba) per-particle passes of the waypoint swarm (mdm_montecarlo.engines.waypoint_swarm):
what happens on a particle's arrival at its waypoint, over the arrivals (run, vehicle) in one
loop each instead of a dozen masked numpy assignments over every particle."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]


@compiled
def take_readings(
    run: IntArray,
    lane: IntArray,
    position: FloatArray,
    reading: FloatArray,
    source: IntArray,
    current: FloatArray,
    own_position: FloatArray,
    own_fitness: FloatArray,
    own_source: IntArray,
) -> FloatArray:
    """For every arrival (``run``, ``lane``): its ``reading`` there becomes its ``current``
    fitness, and a strictly better one its personal best (``own_*``), in place. Returns the
    arrivals' personal bests' fitness before (ARPSO's evolution speed)."""
    previous = np.empty(run.shape[0])
    for a in range(run.shape[0]):
        r = run[a]
        i = lane[a]
        previous[a] = own_fitness[r, i]
        current[r, i] = reading[r, i]
        if reading[r, i] > own_fitness[r, i]:
            own_position[r, i, 0] = position[r, i, 0]
            own_position[r, i, 1] = position[r, i, 1]
            own_fitness[r, i] = reading[r, i]
            own_source[r, i] = source[r, i]
    return previous


@compiled
def steer(
    run: IntArray,
    lane: IntArray,
    follow: BoolArray,
    position: FloatArray,
    move: FloatArray,
    area: FloatArray,
    waypoint: FloatArray,
    velocity: FloatArray,
) -> None:
    """For every arrival (``run``, ``lane``): where it ``follow``s a best, its next waypoint is
    position + ``move`` (arrivals, 2) clipped to the area (0 .. area per axis); its velocity
    becomes the displacement to its next waypoint (the others' waypoints are already drawn).
    In place."""
    for a in range(run.shape[0]):
        r = run[a]
        i = lane[a]
        for k in range(2):
            x = position[r, i, k]
            if follow[a]:
                waypoint[r, i, k] = min(max(x + move[a, k], 0.0), area[k])
            velocity[r, i, k] = waypoint[r, i, k] - x
