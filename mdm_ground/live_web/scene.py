"""What does not change during a run: the search area, the fence, the targets, the origin."""

from __future__ import annotations

from typing import Any

from companion.fence_from_profile import fence_for
from mdm_ground.live_web.event_log import LOG_KEPT
from mdm_ground.live_web.fleet_state import TRACK_KEPT
from mdm_profiles import MissionProfile


def scene(
    profile: MissionProfile, *, vehicles: int, show_targets: bool, tiles: str | None = None
) -> dict[str, Any]:
    """The page's fixed layer, in metres north/east of the profile's origin; ``tiles`` a
    map-tile URL template the browser draws under it."""
    o = profile.origin
    return {
        "profile": profile.name,
        "vehicles": vehicles,
        "origin": {"lat": o.lat, "lon": o.lon},
        "area": {"north": profile.area.north, "east": profile.area.east},
        "fence": [[float(n), float(e)] for n, e in fence_for(profile).vertices],
        "targets": [
            {
                "north": t.north,
                "east": t.east,
                "false_target": t.false_target,
                "appear": t.appear,
                "moving": profile.target_motion is not None,
            }
            for t in profile.targets
        ]
        if show_targets
        else [],
        "real_targets": sum(not t.false_target for t in profile.targets),
        "levels": len(profile.sensors),
        "sensors": [{"name": s.name, "radius": s.radius} for s in profile.sensors],
        "ceiling": ceiling(profile),
        "track_kept": TRACK_KEPT,
        "log_kept": LOG_KEPT,
        "tiles": tiles,
    }


def ceiling(profile: MissionProfile) -> float | None:
    """The site's ceiling (``site.max_altitude``, m above the take-off point) where the
    profile has a site that sets one; None otherwise. Read with getattr: profiles of a
    schema without the field have none."""
    value = getattr(profile.site, "max_altitude", None) if profile.site is not None else None
    return float(value) if isinstance(value, int | float) else None
