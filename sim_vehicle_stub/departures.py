"""When each target of a free walk leaves the area: the ground-truth ``target_gone`` events.

The times come from the world's own tracks (``TargetTracks.departures``, the solver the
Monte-Carlo engine scores ``mission.ts_rule: confirmed_or_gone`` with), so the emulator and the
engine agree on every departure of the same path. Only a free walk leaves the area: the other
boundaries keep the targets inside.
"""

from __future__ import annotations

import math

import numpy as np

from mdm_core.world import TargetSpec, TargetTracks
from sim_vehicle_stub.events import EventLog

HORIZON_NODES = 32
"""Path segments solved at first; the horizon doubles each time sim time passes it."""


class Departures:
    """Logs each target's departure once, at the first tick at or after it."""

    def __init__(self, spec: TargetSpec, tracks: TargetTracks, events: EventLog) -> None:
        self.spec = spec
        self.tracks = tracks
        self.events = events
        self._logged = np.zeros(spec.count, dtype=bool)
        self._times = np.full(spec.count, np.inf)
        self._horizon = math.inf
        walk = tracks.walk
        if walk is not None and walk.boundary == "free":
            self._horizon = HORIZON_NODES * tracks.grid_dt
            self._times = tracks.departures(self._horizon)[0]
        self._due = self._next_due()

    @property
    def times(self) -> np.ndarray:
        """(m,) each target's departure, sim s (inf: never, or not within the horizon solved
        so far)."""
        return self._times

    def tick(self, t: float) -> None:
        """Log ``target_gone`` for every target whose departure is at or before ``t``."""
        if t < self._due:
            return
        while t > self._horizon:
            # Departures within the old horizon stay as they were: the path is drawn once.
            self._horizon *= 2.0
            self._times = self.tracks.departures(self._horizon)[0]
        for k in np.flatnonzero((self._times <= t) & ~self._logged):
            self._logged[k] = True
            left = float(self._times[k])
            where = self.tracks.positions(np.zeros(1, dtype=np.intp), np.array([left]))[0, k]
            self.events.write(
                t,
                "target_gone",
                target=int(k),
                left_at=left,
                north=float(where[0]),
                east=float(where[1]),
                false_target=bool(self.spec.false_mask[k]),
            )
        self._due = self._next_due()

    def _next_due(self) -> float:
        """The sim time of the next thing to do: a departure to log, or the horizon to extend."""
        left = self._times[~self._logged]
        return min(float(left.min(initial=math.inf)), self._horizon)
