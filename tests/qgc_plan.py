"""A QGroundControl ``.plan`` as QGroundControl stores one: a takeoff, a Survey (a complex item
whose transects QGroundControl has already expanded into the waypoints of
``TransectStyleComplexItem.Items``), a return to launch, an inclusion polygon and a rally
point. Written by hand here from the file format (plan version 1, mission 2, survey 5)."""

from __future__ import annotations

import json
import math
from typing import Any

_M_PER_DEG_LAT = 111_320.0


def _offset(home: tuple[float, float], north: float, east: float) -> tuple[float, float]:
    lat, lon = home
    return (
        lat + north / _M_PER_DEG_LAT,
        lon + east / (_M_PER_DEG_LAT * math.cos(math.radians(lat))),
    )


def _simple(command: int, frame: int, params: list[Any], jump_id: int) -> dict[str, Any]:
    return {
        "autoContinue": True,
        "command": command,
        "doJumpId": jump_id,
        "frame": frame,
        "params": params,
        "type": "SimpleItem",
    }


def lawnmower(
    legs: int, length: float, spacing: float, start: tuple[float, float]
) -> list[tuple[float, float]]:
    """The survey's turn points (north, east from home): legs running north, ``spacing`` apart
    eastwards, alternating direction, from ``start``."""
    points = []
    for k in range(legs):
        east = start[1] + k * spacing
        a, b = start[0], start[0] + length
        if k % 2:
            a, b = b, a
        points += [(a, east), (b, east)]
    return points


def survey_plan(
    home: tuple[float, float, float],
    waypoints: list[tuple[float, float]],
    alt: float,
    firmware: int,
) -> dict[str, Any]:
    """The ``.plan`` (a dict, ``json.dumps`` of which is the file) flying ``waypoints`` (north,
    east metres from home) at ``alt`` m above home; ``firmware`` 3 ArduPilot, 12 PX4."""
    lat0, lon0, amsl = home
    items = [_simple(22, 3, [0, 0, 0, None, lat0, lon0, alt], 1)]
    survey_items = []
    for k, (n, e) in enumerate(waypoints):
        lat, lon = _offset((lat0, lon0), n, e)
        survey_items.append(_simple(16, 3, [0, 0, 0, None, lat, lon, alt], k + 2))
    polygon = [
        list(_offset((lat0, lon0), n, e)) for n, e in waypoints[:: max(1, len(waypoints) - 1)]
    ]
    items.append(
        {
            "TransectStyleComplexItem": {
                "CameraCalc": {"AdjustedFootprintSide": 20, "CameraName": "Manual (no camera specs)",
                               "DistanceToSurface": alt, "DistanceToSurfaceRelative": True,
                               "version": 1},
                "CameraShots": 0,
                "CameraTriggerInTurnAround": True,
                "HoverAndCapture": False,
                "Items": survey_items,
                "Refly90Degrees": False,
                "TurnAroundDistance": 0,
                "VisualTransectPoints": [list(_offset((lat0, lon0), n, e)) for n, e in waypoints],
                "version": 1,
            },
            "angle": 0,
            "complexItemType": "survey",
            "entryLocation": 0,
            "flyAlternateTransects": False,
            "polygon": polygon,
            "splitConcavePolygons": False,
            "type": "ComplexItem",
            "version": 5,
        }
    )  # fmt: skip
    items.append(_simple(20, 2, [0, 0, 0, 0, 0, 0, 0], len(waypoints) + 2))
    fence = [list(_offset((lat0, lon0), n, e)) for n, e in ((-300, -300), (-300, 600),
                                                           (600, 600), (600, -300))]  # fmt: skip
    return {
        "fileType": "Plan",
        "geoFence": {"circles": [], "polygons": [{"inclusion": True, "polygon": fence,
                                                  "version": 1}], "version": 2},
        "groundStation": "QGroundControl",
        "mission": {
            "cruiseSpeed": 15,
            "firmwareType": firmware,
            "globalPlanAltitudeMode": 1,
            "hoverSpeed": 5,
            "items": items,
            "plannedHomePosition": [lat0, lon0, amsl],
            "vehicleType": 2,
            "version": 2,
        },
        "rallyPoints": {"points": [[*_offset((lat0, lon0), 50, 0), 20]], "version": 2},
        "version": 1,
    }  # fmt: skip


def plan_text(plan: dict[str, Any]) -> str:
    return json.dumps(plan, indent=4)
