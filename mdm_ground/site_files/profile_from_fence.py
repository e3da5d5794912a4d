"""A profile that flies inside an imported fence: ``site.geofence`` replaced (clockwise), and the
origin and search area derived from the fence (its bounding rectangle in the local north/east
frame, grown by a margin) or kept as they are."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

from pydantic import ValidationError
from shapely.geometry import Polygon, box

from companion.fence_from_profile import guidance_fence
from companion.link.local_frame import LocalFrame
from mdm_ground.site_files.fence_polygon import FencePolygon, SiteFileError
from mdm_ground.site_files.site_layers import clockwise
from mdm_profiles import MissionProfile
from mdm_profiles.loader import describe_errors

ORIGIN_TOLERANCE = 1e-3
"""m: the origin is moved until the fence's south-west bound is this close to the margin (the
local frame turns with its origin: 0.3 mm per metre moved, so a first guess is off by up to
0.6 m across 2 km)."""
AREA_STEP = 0.1
"""m: the search area's sides are rounded up to this."""

TargetRule = Literal["ground", "frame", "fit"]


@dataclass(frozen=True)
class FenceImport:
    """How the fence becomes the profile's site."""

    margin: float = 0.0
    """m between the fence's bounding rectangle and the search area's edges."""
    keep_area: bool = False
    """Keep the profile's origin and area; only ``site.geofence`` changes."""
    targets: TargetRule = "ground"
    """ground: each target keeps its WGS84 position (re-expressed from the new origin); frame:
    it keeps its (north, east) metres, now from the new origin; fit: its place in the search
    area, scaled from the old area's sides to the new ones (a profile from another site)."""
    alt: float | None = None
    """Origin altitude AMSL, m (default: the profile's)."""


def _bounds(frame: LocalFrame, fence: FencePolygon) -> tuple[float, float, float, float]:
    """min north, min east, max north, max east of the fence in ``frame``."""
    local = [frame.to_local(lat, lon, frame.alt)[:2] for lat, lon in fence.vertices]
    norths, easts = [p[0] for p in local], [p[1] for p in local]
    return min(norths), min(easts), max(norths), max(easts)


def _origin(
    fence: FencePolygon, alt: float, margin: float, source: str
) -> tuple[LocalFrame, float, float]:
    """The frame whose (0, 0) lies ``margin`` south and west of the fence's bounds, and the
    area's (north, east) extent."""
    frame = LocalFrame(*fence.vertices[0], alt)
    for _ in range(10):
        south, west, north, east = _bounds(frame, fence)
        if abs(south - margin) <= ORIGIN_TOLERANCE and abs(west - margin) <= ORIGIN_TOLERANCE:
            return frame, north + margin, east + margin
        lat, lon, _ = frame.to_geodetic(south - margin, west - margin, 0.0)
        frame = LocalFrame(lat, lon, alt)
    raise SiteFileError(f"{source}: the origin did not settle within {ORIGIN_TOLERANCE} m")


def _round_up(value: float) -> float:
    return round(math.ceil(value / AREA_STEP - 1e-9) * AREA_STEP, 1)


def _move_targets(
    data: dict[str, Any], base: MissionProfile, frame: LocalFrame, rule: TargetRule
) -> None:
    """Re-place ``data``'s targets (base's, in its frame) in the new ``frame`` and area."""
    old = LocalFrame(base.origin.lat, base.origin.lon, base.origin.alt)
    for t in data["targets"]:
        if rule == "ground":
            lat, lon, _ = old.to_geodetic(t["north"], t["east"], 0.0)
            n, e, _ = frame.to_local(lat, lon, base.origin.alt)
        elif rule == "fit":
            n = t["north"] * data["area"]["north"] / base.area.north
            e = t["east"] * data["area"]["east"] / base.area.east
        else:
            continue
        t["north"], t["east"] = round(n, 1), round(e, 1)


def profile_with_fence(
    base: MissionProfile, fence: FencePolygon, source: str, how: FenceImport
) -> MissionProfile:
    """``base`` flying inside ``fence`` (read from ``source``, named in every error): the new
    profile is validated as a loaded one is, and its fence must take the guidance's inset."""
    data = base.model_dump(mode="json")
    site = data.get("site") or {"name": ""}
    # clockwise, as QGC's plans and field-duebendorf hold it: a fence read from any format
    # gives the same profile
    site["geofence"] = [{"lat": lat, "lon": lon} for lat, lon in clockwise(fence.vertices)]
    data["site"] = site
    alt = base.origin.alt if how.alt is None else how.alt
    if not math.isfinite(alt):
        raise SiteFileError(f"--alt {alt}: must be a finite altitude AMSL, m")
    if not how.keep_area:
        if how.margin < 0 or not math.isfinite(how.margin):
            raise SiteFileError(f"--margin {how.margin:g}: must be a finite length >= 0 m")
        frame, north, east = _origin(fence, alt, how.margin, source)
        data["origin"] = {"lat": frame.lat, "lon": frame.lon, "alt": alt}
        data["area"] = {"north": _round_up(north), "east": _round_up(east)}
        _move_targets(data, base, frame, how.targets)
    else:
        data["origin"]["alt"] = alt
    try:
        profile = MissionProfile.model_validate(data)
    except ValidationError as exc:
        described = describe_errors(f"{base.name} with the fence of {source}", exc)
        if "outside the area" in described:
            described += (
                f"\n  (targets are placed by --targets {how.targets}: rehearsal "
                "targets must lie inside the new search area)"
            )
        raise SiteFileError(described) from None
    try:
        inner = guidance_fence(profile)
    except ValueError as exc:
        raise SiteFileError(
            f"{source}: {exc} (site.fence_inset "
            f"{profile.site.fence_inset if profile.site else 0:g} m)"
        ) from exc
    area = box(0.0, 0.0, profile.area.north, profile.area.east)
    if not Polygon(inner.vertices).intersects(area):
        raise SiteFileError(
            f"{source}: the fence lies {Polygon(inner.vertices).distance(area):.0f}"
            " m from the profile's search area (--keep-area): another site?"
        )
    return profile
