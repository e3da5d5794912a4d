"""QGroundControl `.plan` files (JSON, QGC's documented Plan File Format): the fence is read
from ``geoFence.polygons``; a written plan holds the profile's fence and its origin as the
planned home, and no mission items or rally points (docs/companion.md, "Field profiles")."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from mdm_ground.site_files.fence_polygon import Candidate, FencePolygon, SiteFileError, pick_fence
from mdm_ground.site_files.formats import FIRMWARE_TYPES
from mdm_ground.site_files.site_layers import SiteLayers, clockwise

GEOFENCE_VERSION = 2
"""The geoFence object's version QGroundControl reads and writes (it ignores version 1)."""
MAV_TYPE_QUADROTOR = 2


def _as_list(source: str, where: str, value: object) -> list[Any]:
    if not isinstance(value, list):
        raise SiteFileError(f"{source}: {where} must be a list, got {type(value).__name__}")
    return value


def read_plan(path: Path) -> FencePolygon:
    """The one inclusion polygon of a QGC plan's geofence; mission items and rally points are
    not read. Circles, exclusion polygons, several polygons and a pre-version-2 geofence are
    refused."""
    source = str(path)
    try:
        plan = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise SiteFileError(f"{source}: not a QGroundControl plan (not JSON: {exc})") from exc
    if not isinstance(plan, dict) or plan.get("fileType") != "Plan":
        kind = plan.get("fileType") if isinstance(plan, dict) else type(plan).__name__
        raise SiteFileError(
            f"{source}: not a QGroundControl plan (fileType {kind!r}, expected 'Plan')"
        )
    fence = plan.get("geoFence")
    if not isinstance(fence, dict):
        raise SiteFileError(
            f"{source}: the plan has no geoFence: draw the fence in QGC's Plan "
            "view (Fence) and save the plan again"
        )
    if fence.get("version") != GEOFENCE_VERSION:
        raise SiteFileError(
            f"{source}: geoFence version {fence.get('version')!r}: only version "
            f"{GEOFENCE_VERSION} is read (QGroundControl ignores older fences "
            "too); open and save the plan in a current QGC"
        )
    circles = _as_list(source, "geoFence.circles", fence.get("circles", []))
    if circles:
        raise SiteFileError(
            f"{source}: geoFence.circles[0] is a circular fence: the companion "
            "keeps one inclusion polygon; draw the fence as a polygon"
        )
    candidates = []
    for k, item in enumerate(_as_list(source, "geoFence.polygons", fence.get("polygons", []))):
        where = f"geoFence.polygons[{k}]"
        if not isinstance(item, dict) or not isinstance(item.get("inclusion"), bool):
            raise SiteFileError(f"{source}: {where} needs 'inclusion' (true or false)")
        ring = _as_list(source, f"{where}.polygon", item.get("polygon"))
        for i, vertex in enumerate(ring):
            _as_list(source, f"{where}.polygon[{i}]", vertex)
        candidates.append(Candidate(where, ring, inclusion=item["inclusion"]))
    return pick_fence(source, candidates)


def plan_document(layers: SiteLayers, firmware: str) -> dict[str, Any]:
    """The plan QGroundControl opens: the fence as its one inclusion polygon (clockwise, as
    QGC's format asks; a clockwise profile fence keeps its order), the profile's
    origin as planned home, an empty mission (QGC's Upload sends the mission and rally points
    with the fence: none are added, so the vehicle gets the fence and nothing else)."""
    lat, lon, alt = layers.home
    return {
        "fileType": "Plan",
        "geoFence": {
            "circles": [],
            "polygons": [
                {
                    "inclusion": True,
                    "polygon": [[a, b] for a, b in clockwise(layers.fence)],
                    "version": 1,
                }
            ],
            "version": GEOFENCE_VERSION,
        },
        "groundStation": "mdm-search companion",
        "mission": {
            "cruiseSpeed": layers.speed,
            "firmwareType": FIRMWARE_TYPES[firmware],
            "globalPlanAltitudeMode": 1,
            "hoverSpeed": layers.speed,
            "items": [],
            "plannedHomePosition": [lat, lon, alt],
            "vehicleType": MAV_TYPE_QUADROTOR,
            "version": 2,
        },
        "rallyPoints": {"points": [], "version": 2},
        "version": 1,
    }


def write_plan(layers: SiteLayers, path: Path, firmware: str) -> None:
    """:func:`plan_document` as a file, indented as QGroundControl saves plans."""
    path.write_text(json.dumps(plan_document(layers, firmware), indent=4) + "\n", encoding="utf-8")
