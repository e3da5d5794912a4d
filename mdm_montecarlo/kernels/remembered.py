"""Which targets each lane remembers confirming, kept between events instead of recomputed.

A target is 'remembered' by a lane while it lies within the policy's memory_radius R of a
position the lane confirmed (SearchPolicy.memory_distance2). That answer only changes when the
lane confirms again or a target crosses the R circle. Targets move at most at the tracks' top
speed v, so an answer computed at time t holds until t + min |d - R| / v over the targets; fixed
targets (v = 0) keep it until the next confirmation. A newly drawn path segment that raises the
top speed voids every window. The stale answers are recomputed in one compiled loop (the
targets' positions as TargetTracks.positions interpolates them, the nearest remembered target
as memory_distance2 finds it), which also gives the engine its eligible contacts.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled
from mdm_core.search.policy import PolicyState
from mdm_core.world import TargetTracks
from mdm_core.world.targets import NODE_EPS
from mdm_montecarlo.kernels.compiled_step import nearest2

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]


class RememberedTargets:
    """Cached SearchPolicy.known for every lane of a block, with per-lane validity windows.

    The engine's compiled round loop (``block_rounds``) works on these arrays directly;
    ``eligible`` and ``forget`` are one round's worth of it (tests compare them with
    SearchPolicy.known)."""

    def __init__(self, memory_radius: float, tracks: TargetTracks, lanes: int, targets: int):
        self.radius = memory_radius
        self._tracks = tracks
        self.known = np.zeros((lanes, targets), dtype=bool)
        """(lanes, m) the cached answers."""
        self.until = np.full(lanes, -np.inf)
        """(lanes,) the time each lane's answers hold until."""
        self.speed = np.array([tracks.max_speed])
        """(1,) the target speed the windows were computed with."""

    def eligible(
        self, state: PolicyState, lanes: IntArray, runs: IntArray, t: FloatArray, exact: BoolArray
    ) -> BoolArray:
        """(len(lanes), m): False for the targets the lanes (of the given runs, at their times
        t) with ``exact`` set know they confirmed (SearchPolicy.known), True elsewhere."""
        visible = self._tracks.max_speed
        seg_start, seg_velocity = self._tracks.segments(float(t.max(initial=0.0)))
        return eligible(
            self.known,
            self.until,
            self.speed,
            visible,
            state.memory,
            state.memory_count,
            lanes,
            runs,
            t,
            exact,
            seg_start,
            seg_velocity,
            self._tracks.grid_dt,
            self._tracks.moving,
            self.radius,
            np.empty((lanes.shape[0], self.known.shape[1]), dtype=bool),
        )

    def forget(self, lanes: IntArray) -> None:
        """The lanes' memory changed (a confirmation): recompute their answer next time."""
        self.until[lanes] = -np.inf


@compiled
def eligible(
    known: BoolArray,
    until: FloatArray,
    speed: FloatArray,
    visible: float,
    memory: FloatArray,
    memory_count: IntArray,
    lanes: IntArray,
    runs: IntArray,
    t: FloatArray,
    exact: BoolArray,
    seg_start: FloatArray,
    seg_velocity: FloatArray,
    grid_dt: float,
    moving: bool,
    radius: float,
    out: BoolArray,
) -> BoolArray:
    """RememberedTargets.eligible's loop: the answers of the stale lanes recomputed in place
    (``known``, ``until``), then every lane's row of ``out`` (n, m), which it returns: not
    known on the exact lanes, True on the others. ``visible`` is the tracks' top speed before
    this round's growth: a higher one than ``speed[0]`` voids every window first."""
    if visible > speed[0]:
        speed[0] = visible
        until[:] = -np.inf
    n, m = lanes.shape[0], known.shape[1]
    r2 = radius * radius
    for i in range(n):
        if not exact[i]:
            for j in range(m):
                out[i, j] = True
            continue
        lane = lanes[i]
        if t[i] >= until[lane]:
            row = runs[i] if moving else 0
            k = math.floor(t[i] / grid_dt + NODE_EPS) if moving else 0
            offset = t[i] - k * grid_dt if moving else 0.0
            margin = np.inf
            for j in range(m):
                x = seg_velocity[row, k, j, 0] * offset + seg_start[row, k, j, 0]
                y = seg_velocity[row, k, j, 1] * offset + seg_start[row, k, j, 1]
                d2 = nearest2(memory, memory_count[lane], lane, x, y)
                known[lane, j] = d2 <= r2
                margin = min(margin, abs(math.sqrt(d2) - radius))
            until[lane] = t[i] + margin / speed[0] if speed[0] > 0 else np.inf
        for j in range(m):
            out[i, j] = not known[lane, j]
    return out
