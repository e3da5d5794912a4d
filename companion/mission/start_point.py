"""Where a vehicle starts its search: the profile's start rule (periphery_even,
periphery_random), drawn as the engine and the emulator draw it (Scenario.live_run with the
mission's seed), moved inside the guidance fence where the periphery lies outside it."""

from __future__ import annotations

from companion.geofence import Geofence
from mdm_core.world.scenario import Scenario
from mdm_profiles import MissionProfile


def start_point(
    profile: MissionProfile, seed: int, vehicle: int, fence: Geofence
) -> tuple[float, float]:
    """(north, east) in the profile's frame that ``vehicle`` transits to before its search."""
    start, _ = Scenario.from_profile(profile).live_run(
        seed, profile.fleet.vehicles, profile.fleet.start
    )
    return fence.clamp_xy(float(start[vehicle, 0]), float(start[vehicle, 1]))
