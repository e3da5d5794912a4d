"""Which targets each lane remembers confirming, kept between events instead of recomputed.

A target is 'remembered' by a lane while it lies within the policy's memory_radius R of a
position the lane confirmed (SearchPolicy.memory_distance2). That answer only changes when the
lane confirms again or a target crosses the R circle. Targets move at most at the tracks' top
speed v, so an answer computed at time t holds until t + min |d - R| / v over the targets; fixed
targets (v = 0) keep it until the next confirmation. A newly drawn path segment that raises the
top speed voids every window.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mdm_core.search import SearchPolicy
from mdm_core.search.policy import PolicyState
from mdm_core.world import TargetTracks

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]


class RememberedTargets:
    """Cached SearchPolicy.known for every lane of a block, with per-lane validity windows."""

    def __init__(self, policy: SearchPolicy, tracks: TargetTracks, lanes: int, targets: int):
        self._policy = policy
        self._tracks = tracks
        self._known = np.zeros((lanes, targets), dtype=bool)
        self._until = np.full(lanes, -np.inf)
        self._speed = tracks.max_speed

    def known(
        self, state: PolicyState, lanes: IntArray, runs: IntArray, t: FloatArray
    ) -> BoolArray:
        """(len(lanes), m) known targets of the lanes (of the given runs) at their times t.

        The targets' positions are looked up only for the lanes whose answer is stale."""
        if self._tracks.max_speed > self._speed:
            self._speed = self._tracks.max_speed
            self._until[:] = -np.inf
        stale = np.flatnonzero(t >= self._until[lanes])
        if stale.size:
            radius = self._policy.config.memory_radius
            due = lanes[stale]
            d2 = self._policy.memory_distance2(
                state, due, self._tracks.positions(runs[stale], t[stale])
            )
            self._known[due] = d2 <= radius * radius
            if self._speed > 0:
                margin = np.abs(np.sqrt(d2) - radius).min(axis=1)
                self._until[due] = t[stale] + margin / self._speed
            else:
                self._until[due] = np.inf
        return self._known[lanes]

    def forget(self, lanes: IntArray) -> None:
        """The lanes' memory changed (a confirmation): recompute their answer next time."""
        self._until[lanes] = -np.inf
