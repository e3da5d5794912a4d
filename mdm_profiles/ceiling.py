"""The ceiling: every vehicle's altitude layer (``fleet.altitude + i x fleet.altitude_step``,
Assumption III) under ``site.max_altitude`` (m above the take-off point; 120 m, the usual legal
ceiling, for profiles without a site). Checked before anything arms."""

from __future__ import annotations

import math

from mdm_profiles.errors import ProfilesError
from mdm_profiles.schema import DEFAULT_MAX_ALTITUDE, MissionProfile


class CeilingError(ProfilesError, ValueError):
    """A team whose layers do not fit under the ceiling; the message says how many fit."""


def ceiling(profile: MissionProfile) -> float:
    """The highest altitude a vehicle of ``profile`` may fly, m above its take-off point."""
    return profile.site.max_altitude if profile.site is not None else DEFAULT_MAX_ALTITUDE


def vehicles_that_fit(profile: MissionProfile) -> int:
    """How many layers fit under the ceiling with the profile's altitude and spacing."""
    top, fleet = ceiling(profile), profile.fleet
    if fleet.altitude > top:
        return 0
    if fleet.altitude_step == 0:
        return fleet.vehicles
    return math.floor((top - fleet.altitude) / fleet.altitude_step + 1e-9) + 1


def check_ceiling(profile: MissionProfile, vehicles: int) -> None:
    """Refuse a team of ``vehicles`` whose top layer is above the ceiling."""
    fleet = profile.fleet
    top_layer = fleet.altitude + (vehicles - 1) * fleet.altitude_step
    limit = ceiling(profile)
    if top_layer <= limit:
        return
    where = "site.max_altitude" if profile.site is not None else "the default ceiling"
    raise CeilingError(
        f"profile {profile.name!r}: {vehicles} vehicles fly layers up to {top_layer:g} m "
        f"(fleet.altitude {fleet.altitude:g} m + {vehicles - 1} x fleet.altitude_step "
        f"{fleet.altitude_step:g} m), above {where} {limit:g} m: {vehicles_that_fit(profile)} "
        f"vehicles fit with that spacing"
    )
