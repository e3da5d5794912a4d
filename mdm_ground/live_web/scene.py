"""What does not change during a run: the search area, the fence, the targets, the origin."""

from __future__ import annotations

from typing import Any

from companion.fence_from_profile import fence_for
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
        "tiles": tiles,
    }
