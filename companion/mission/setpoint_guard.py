"""The last check before a setpoint is encoded: nothing non-finite, nothing outside the
vehicle's envelope (the profile's speed, the fence, its altitude layer) ever leaves.

Such a setpoint is a bug upstream (a position the telemetry check let through, guidance): it is
logged with its cause and replaced by a hold (zero velocity, or the last good point).
"""

from __future__ import annotations

import math
from collections import Counter

from companion.geofence import Geofence
from companion.guidance import GuidanceConfig, NedSetpoint
from companion.link.base import SetpointKind

_EPS = 1e-6


class SetpointGuard:
    """Checks every setpoint of one vehicle; counts what it checked and what it replaced."""

    def __init__(
        self, guide: GuidanceConfig, fence: Geofence, kind: SetpointKind, layer: float
    ) -> None:
        self.guide = guide
        self.fence = fence
        self.kind = kind
        self.layer = layer
        """Metres above the vehicle's altitude a position setpoint may ask for (half the
        fleet's vertical separation: the next vehicle's layer starts there)."""
        self.checked = 0
        self.refused: Counter[str] = Counter()
        self._last_good: NedSetpoint | None = None

    def cause(self, sp: NedSetpoint) -> tuple[str, str] | None:
        """Why ``sp`` must not be sent (the kind of fault, in words with its figures), or None."""
        values = (sp.north, sp.east, sp.down, sp.vn, sp.ve, sp.vd)
        if not all(math.isfinite(v) for v in values):
            return "non-finite", f"non-finite value in {sp}"
        g = self.guide
        if self.kind == "velocity":
            speed = math.hypot(sp.vn, sp.ve)
            if speed > g.speed + _EPS:
                return "speed", f"speed {speed:.6g} m/s above the profile's {g.speed:g}"
            if abs(sp.vd) > g.max_climb + _EPS:
                return "vertical speed", f"vertical speed {sp.vd:.6g} m/s beyond {g.max_climb:g}"
            if speed > 0.0 and not self.fence.contains((sp.north, sp.east)):
                return "fence", f"steering to ({sp.north:.1f}, {sp.east:.1f}), outside the fence"
            return None
        if not self.fence.contains((sp.north, sp.east)):
            return "fence", f"point ({sp.north:.1f}, {sp.east:.1f}) outside the fence"
        if -sp.down > g.altitude + self.layer + _EPS:
            return "altitude", (
                f"altitude {-sp.down:.6g} m above the layer ({g.altitude:g} + {self.layer:g})"
            )
        return None

    def safe(self, sp: NedSetpoint) -> tuple[NedSetpoint | None, tuple[str, str] | None]:
        """``sp`` when it may be sent; else a hold in its place (None: no safe point known for
        a position setpoint: send nothing), and why (:meth:`cause`)."""
        self.checked += 1
        why = self.cause(sp)
        if why is None:
            self._last_good = sp
            return sp, None
        self.refused[why[0]] += 1
        last = self._last_good
        if self.kind == "velocity":
            north, east = (0.0, 0.0) if last is None else (last.north, last.east)
            return NedSetpoint(north, east, -self.guide.altitude, 0.0, 0.0, 0.0), why
        return last, why
