"""Compiled (numba) per-particle passes of the waypoint swarm (mdm_montecarlo.waypoint_swarm):
what happens on a particle's arrival at its waypoint, over (runs, vehicles) in one loop each
instead of a dozen masked numpy assignments."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]


@compiled
def take_readings(
    reached: BoolArray,
    position: FloatArray,
    reading: FloatArray,
    source: IntArray,
    current: FloatArray,
    own_position: FloatArray,
    own_fitness: FloatArray,
    own_source: IntArray,
) -> FloatArray:
    """For every particle that ``reached`` its waypoint: its ``reading`` there becomes its
    ``current`` fitness, and a strictly better one its personal best (``own_*``), in place.
    Returns the personal bests' fitness before (ARPSO's evolution speed)."""
    previous = own_fitness.copy()
    runs, n = reached.shape
    for r in range(runs):
        for i in range(n):
            if reached[r, i]:
                current[r, i] = reading[r, i]
                if reading[r, i] > own_fitness[r, i]:
                    own_position[r, i, 0] = position[r, i, 0]
                    own_position[r, i, 1] = position[r, i, 1]
                    own_fitness[r, i] = reading[r, i]
                    own_source[r, i] = source[r, i]
    return previous


@compiled
def steer(
    reached: BoolArray,
    follow: BoolArray,
    position: FloatArray,
    move: FloatArray,
    area: FloatArray,
    waypoint: FloatArray,
    velocity: FloatArray,
) -> None:
    """For every particle that ``reached`` its waypoint: where it ``follow``s a best, its next
    waypoint is position + move clipped to the area (0 .. area per axis); its velocity becomes
    the displacement to its next waypoint (the others' waypoints are already drawn). In place."""
    runs, n = reached.shape
    for r in range(runs):
        for i in range(n):
            if reached[r, i]:
                for a in range(2):
                    x = position[r, i, a]
                    if follow[r, i]:
                        waypoint[r, i, a] = min(max(x + move[r, i, a], 0.0), area[a])
                    velocity[r, i, a] = waypoint[r, i, a] - x
