"""A battery reserve that knows the way home: the percent the flight home needs, at the drain
measured so far in this flight, so the search ends while there is enough left to come back and
land with the profile's reserve (``site.battery_reserve``). docs/companion.md, "Battery"."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from mdm_profiles.schema import SiteSpec


@dataclass(frozen=True)
class ReserveRule:
    """The reserve and how the end action flies home (profile keys ``site.battery_reserve``,
    ``site.return_speed``, ``site.descent_speed``)."""

    reserve: float
    """Percent left at landing."""
    horizontal: float
    """m/s toward home; 0: the end action lands where it is (LAND)."""
    descent: float
    """m/s down to the ground."""

    def at_most(self, speed: float | None) -> ReserveRule:
        """The rule with the way home flown no faster than ``speed`` m/s (the autopilot's own
        return speed, where it was read)."""
        if speed is None or speed <= 0 or self.horizontal <= speed:
            return self
        return replace(self, horizontal=speed)

    def seconds_home(self, distance: float, altitude: float) -> float:
        """Vehicle seconds from ``distance`` m out (horizontal) and ``altitude`` m up to the
        ground at home."""
        across = distance / self.horizontal if self.horizontal > 0 else 0.0
        return across + max(altitude, 0.0) / self.descent


class DrainMeter:
    """Percent per vehicle second, from the first reading airborne in this flight to now (the
    integer percent of SYS_STATUS: 0 until the first percent has gone)."""

    def __init__(self) -> None:
        self._first: tuple[float, int] | None = None

    def note(self, t: float, remaining: int) -> float:
        """The drain rate at mission time ``t`` with ``remaining`` percent left (airborne)."""
        if self._first is None or remaining > self._first[1]:
            self._first = (t, remaining)  # the first reading, or a new pack
        t0, first = self._first
        return (first - remaining) / (t - t0) if t > t0 else 0.0


def percent_home(rate: float, rule: ReserveRule, distance: float, altitude: float) -> int:
    """Percent the flight home takes at ``rate`` percent/s (rounded up to a whole percent, as
    the autopilot reports it)."""
    return math.ceil(rate * rule.seconds_home(distance, altitude) - 1e-9)


def reserve_rule(site: SiteSpec | None, fleet_speed: float, end_action: str) -> ReserveRule | None:
    """The rule of a site profile (None without a site): toward home at ``site.return_speed``
    (else the fleet's speed) for RTL; LAND comes down where it is. None without a site or
    with ``battery_reserve: null``."""
    if site is None or site.battery_reserve is None:
        return None
    speed = site.return_speed if site.return_speed is not None else fleet_speed
    horizontal = speed if end_action == "rtl" else 0.0
    return ReserveRule(site.battery_reserve, horizontal, site.descent_speed)
