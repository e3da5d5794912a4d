"""The check of the vehicle's positions where they enter the companion (both backends).

A position (LOCAL_POSITION_NED, GLOBAL_POSITION_INT) is taken only when it is finite, in
range, from the autopilot's own component, not older than the last one taken, its clock no
faster than the speed-up allows and its move no faster than the vehicle can fly. Anything else
is dropped and counted by cause. A break that is real (a rebooted vehicle: its clock back near
0, its position at home) is taken once ``confirm`` samples in a row agree with each other: a
reset is recognised from a consistent run of samples, never from one message.
"""

from __future__ import annotations

import logging
import math
from collections import Counter
from dataclasses import dataclass

log = logging.getLogger(__name__)

AUTOPILOT_COMPONENT = 1
"""MAV_COMP_ID_AUTOPILOT1: the component whose HEARTBEAT the link takes, and the only one whose
positions (and so clock) it takes."""


@dataclass(frozen=True)
class TelemetryLimits:
    """What a plausible position is (docs/model.md, "Telemetry checks")."""

    max_speed: float = 60.0
    """Fastest horizontal or vertical move or velocity believed, m/s."""
    max_distance: float = 200_000.0
    """Farthest from the local origin a position may be, m."""
    max_altitude: float = 10_000.0
    """Highest above home, m; lowest: -``max_below``."""
    max_below: float = 500.0
    max_rate: float | None = None
    """Vehicle seconds per wall second the clock may run at most (the speed-up, with margin);
    None: unknown, a forward leap of more than ``leap`` vehicle s must be confirmed."""
    leap: float = 5.0
    slack: float = 1.0
    """Vehicle s of jitter allowed beside ``max_rate`` (a loaded host delivering late)."""
    jitter: float = 5.0
    """Metres of move allowed beside ``max_speed`` (the estimator's own noise and resets)."""
    confirm: int = 3
    """Samples in a row, agreeing with each other, that make a new track (a reboot)."""


_Sample = tuple[float, float, float, float, float]
"""(vehicle time, north, east, down, host wall time) of a position."""


class TelemetryGuard:
    """One vehicle's check of positions; ``dropped`` counts the causes (since the start) and
    :meth:`take_report` hands over what was dropped since it was last asked."""

    def __init__(self, limits: TelemetryLimits | None = None) -> None:
        self.limits = limits or TelemetryLimits()
        self.dropped: Counter[str] = Counter()
        self.accepted = 0
        self.new_tracks = 0
        """Breaks taken after ``confirm`` agreeing samples (a reboot, a reset estimator)."""
        self.last_valid_wall: float | None = None
        """Host perf_counter of the last local position taken."""
        self._reported: Counter[str] = Counter()
        self._tracks: dict[str, _Sample] = {}
        self._candidates: dict[str, list[_Sample]] = {}

    def local(
        self,
        component: int,
        t: float,
        north: float,
        east: float,
        down: float,
        vn: float,
        ve: float,
        vd: float,
        wall: float,
    ) -> bool:
        """Whether to take this LOCAL_POSITION_NED (counted either way)."""
        cause = self._local_cause(component, t, north, east, down, vn, ve, vd)
        ok = self._decide("local", cause, (t, north, east, down, wall))
        if ok:
            self.last_valid_wall = wall
        return ok

    def global_position(
        self,
        component: int,
        t: float,
        lat: float,
        lon: float,
        relative_alt: float,
        north: float,
        east: float,
        wall: float,
    ) -> bool:
        """Whether to take this GLOBAL_POSITION_INT (``north``/``east``: in the profile's frame)."""
        cause = None
        if not _finite(lat, lon) or not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
            cause = "lat/lon out of range"
        else:
            cause = self._static(component, t, north, east, -relative_alt)
        return self._decide("global", cause, (t, north, east, -relative_alt, wall))

    def plausible_local(
        self,
        component: int,
        t: float,
        north: float,
        east: float,
        down: float,
        vn: float,
        ve: float,
        vd: float,
        wall: float,
    ) -> bool:
        """Whether :meth:`local` would take this position at once, changing nothing (the
        pymavlink backend's direct answer asks first, then leaves a doubtful one to it)."""
        if self._local_cause(component, t, north, east, down, vn, ve, vd) is not None:
            return False
        last = self._tracks.get("local")
        return last is not None and self._jump(last, (t, north, east, down, wall)) is None

    def reading(self, t: float, *values: float) -> bool:
        """Whether to take a sensor reading (its time; a contact's position and strength, the
        signal's value): finite, the values within 10 ``max_distance``; counted when not."""
        if not _finite(t, *values):
            self.dropped["non-finite reading"] += 1
            return False
        if max(abs(v) for v in values) > self.limits.max_distance * 10:
            self.dropped["reading out of range"] += 1
            return False
        return True

    def unreadable(self, name: str, exc: Exception) -> None:
        """A message no event can carry (a field of the wrong type, an unknown autopilot):
        counted; logged the 1st, 10th, 100th ... time."""
        self.dropped["unreadable message"] += 1
        n = self.dropped["unreadable message"]
        if n == 10 ** (len(str(n)) - 1):
            log.warning("ignored %s: %s (%d unreadable so far)", name, exc, n)

    def take_report(self) -> dict[str, int]:
        """Causes and counts dropped since the last call."""
        new = self.dropped - self._reported
        self._reported = self.dropped.copy()
        return dict(new)

    def _local_cause(
        self,
        component: int,
        t: float,
        north: float,
        east: float,
        down: float,
        vn: float,
        ve: float,
        vd: float,
    ) -> str | None:
        # one sum: NaN and the infinities carry through it (the per-position cost counts)
        if component == AUTOPILOT_COMPONENT and math.isfinite(
            t + north + east + down + vn + ve + vd
        ):
            cause = self._ranges(t, north, east, down)
            if cause is None and max(abs(vn), abs(ve), abs(vd)) > self.limits.max_speed:
                return "velocity out of range"
            return cause
        return self._static(component, t, north, east, down) or "non-finite"

    def _static(
        self, component: int, t: float, north: float, east: float, down: float
    ) -> str | None:
        if component != AUTOPILOT_COMPONENT:
            return "other component"
        if not _finite(t, north, east, down):
            return "non-finite"
        return self._ranges(t, north, east, down)

    def _ranges(self, t: float, north: float, east: float, down: float) -> str | None:
        lim = self.limits
        if t < 0.0:
            return "time out of range"
        if max(abs(north), abs(east)) > lim.max_distance:
            return "position out of range"
        if not -lim.max_below <= -down <= lim.max_altitude:
            return "altitude out of range"
        return None

    def _jump(self, last: _Sample, s: _Sample) -> str | None:
        """Why ``s`` cannot follow ``last`` on one track, or None."""
        lim = self.limits
        t0, n0, e0, d0, w0 = last
        t, n, e, d, w = s
        dt = t - t0
        if dt < 0.0:
            return "clock went back"
        if dt == 0.0 and n == n0 and e == e0 and d == d0:
            return "duplicate"
        allowed = lim.leap if lim.max_rate is None else lim.max_rate * max(w - w0, 0.0) + lim.slack
        if dt > max(allowed, lim.slack):
            return "clock leapt ahead"
        reach = lim.max_speed * dt + lim.jitter
        if math.hypot(n - n0, e - e0) > reach:
            return "moved too fast"
        if abs(d - d0) > reach:
            return "climbed too fast"
        return None

    def _decide(self, track: str, cause: str | None, s: _Sample) -> bool:
        if cause is not None:
            self.dropped[cause] += 1
            return False
        last = self._tracks.get(track)
        cause = None if last is None else self._jump(last, s)
        if cause is None:
            self._take(track, s)
            return True
        if cause == "duplicate":
            self.dropped[cause] += 1
            return False
        pending = self._candidates.setdefault(track, [])
        if pending and self._jump(pending[-1], s) is not None:
            pending.clear()
        pending.append(s)
        if len(pending) >= self.limits.confirm:
            self.new_tracks += 1
            self._take(track, s)
            return True
        self.dropped[cause] += 1
        return False

    def _take(self, track: str, s: _Sample) -> None:
        self._tracks[track] = s
        self._candidates.pop(track, None)
        if track == "local":
            self.accepted += 1


def _finite(*values: float) -> bool:
    return all(math.isfinite(v) for v in values)
