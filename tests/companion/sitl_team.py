"""What the SITL team tests share: a short copy of field-duebendorf whose rehearsal targets lie
near the start points, and observers on each vehicle's second link (ArduCopter SERIAL1, PX4's
GCS link) that judge the flight without the companions' logs."""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import dataclass
from itertools import combinations
from pathlib import Path
from typing import Any

import yaml

from companion.fence_from_profile import guidance_fence
from companion.mission.start_point import start_point
from mdm_ground.fleet.sitl_team import observer_link
from mdm_ground.fleet.vehicles_file import VehicleEntry
from mdm_profiles import load_profile
from tests.companion.sitl_observer import Observer, Trace

SEARCH_MODES = {"arducopter": {4}, "px4": {6 << 16}}
"""GUIDED (ArduCopter custom mode 4), OFFBOARD (PX4 main mode 6 in bits 16-23)."""
ON_GROUND = 1  # MAV_LANDED_STATE_ON_GROUND


def team_profile(folder: Path, *, vehicles: int, seed: int, duration: float) -> Path:
    """field-duebendorf for ``vehicles`` with a ``duration`` s search; one real rehearsal
    target 30 m from each start point toward the area's centre (a confirmation soon after the
    search starts), the 40, 45, 50, 55 m layers of the profile."""
    p = load_profile("field-duebendorf").model_dump(mode="json", exclude_none=True)
    p["name"] = f"field-team-{os.getpid()}"
    p["fleet"]["vehicles"] = vehicles
    p["sensor_source"] = {"kind": "virtual"}
    p["sensors"] = [
        {"name": "rf-detection", "radius": 400.0},
        {"name": "camera-confirmation", "radius": 60.0},
    ]
    p["policy"]["levels"] = [
        {"distribution": "LS", "step": 200.0},
        {
            "distribution": "BS",
            "step": 80.0,
            "index": {"gamma": 0.1, "index_max": 0.95, "index_min": 0.2, "kappa": 600.0},
        },
    ]
    p["mission"] = {"duration": duration, "ts_cap": duration}
    probe = folder / "probe.yaml"
    probe.write_text(yaml.safe_dump(p, sort_keys=False))
    profile = load_profile(str(probe))
    fence = guidance_fence(profile)
    targets = []
    for v in range(vehicles):
        n, e = start_point(profile, seed, v, fence)
        toward = math.atan2(600.0 - n, 1000.0 - e)
        targets.append(
            {
                "north": round(n + 30.0 * math.sin(toward), 1),
                "east": round(e + 30.0 * math.cos(toward), 1),
            }
        )
    p["targets"] = [*targets, {"north": 200.0, "east": 1500.0, "false_target": True}]
    path = folder / "team.yaml"
    path.write_text(yaml.safe_dump(p, sort_keys=False))
    return path


def fence_polygon(profile: Path) -> list[tuple[float, float]]:
    return [(v.lat, v.lon) for v in load_profile(str(profile)).site.geofence]  # type: ignore[union-attr]


def team_of(out: Path, timeout: float = 300.0) -> list[VehicleEntry]:
    """The vehicles a fleet run flies, from its run.json (written once every link answered)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            run = json.loads((out / "run.json").read_text())
        except (OSError, ValueError):
            time.sleep(0.5)
            continue
        return [
            VehicleEntry.model_validate({k: v for k, v in e.items() if k != "heard_autopilot"})
            for e in run["team"]
        ]
    raise AssertionError(f"no run.json in {out} after {timeout:g} s")


def observe(team: list[VehicleEntry]) -> dict[int, Observer]:
    return {e.index: Observer(observer_link(e), e.system_id) for e in team}


def inside(polygon: list[tuple[float, float]], lat: float, lon: float) -> bool:
    """Ray casting on (lat, lon) itself: the fence in WGS84, no frame of the companion's."""
    found = False
    for (a_lat, a_lon), (b_lat, b_lon) in zip(polygon, polygon[1:] + polygon[:1], strict=True):
        if (a_lon > lon) != (b_lon > lon):
            cross = a_lat + (lon - a_lon) * (b_lat - a_lat) / (b_lon - a_lon)
            if lat < cross:
                found = not found
    return found


def metres(a: tuple[float, float], b: tuple[float, float]) -> float:
    north = math.radians(b[0] - a[0]) * 6_371_000.0
    east = math.radians(b[1] - a[1]) * 6_371_000.0 * math.cos(math.radians(a[0]))
    return math.hypot(north, east)


@dataclass
class Figures:
    """One vehicle as its observer saw it."""

    flown: float
    layer: float
    """Median relative altitude while in the search mode above 30 m, m."""
    samples: int
    outside: int
    armed_ever: bool
    end: str

    def line(self, i: int, kind: str) -> str:
        return (
            f"vehicle {i} ({kind}): {self.flown:.0f} m flown, layer {self.layer:.1f} m, "
            f"{self.samples} airborne GPS samples, {self.outside} outside the fence, "
            f"end {self.end}"
        )


def figures(t: Trace, kind: str, polygon: list[tuple[float, float]]) -> Figures:
    layer = sorted(alt for _, _, alt, mode in t.track if mode in SEARCH_MODES[kind] and alt > 30.0)
    outside = sum(not inside(polygon, lat, lon) for lat, lon, _, _ in t.track)
    end = (
        "landed, disarmed"
        if t.landed_state == ON_GROUND and not t.armed
        else f"landed_state {t.landed_state}, armed {t.armed}"
    )
    median = layer[len(layer) // 2] if layer else float("nan")
    return Figures(t.distance, median, len(t.track), outside, t.armed_ever, end)


def separation_breaches(
    traces: dict[int, Trace],
    *,
    horizontal: float = 50.0,
    vertical: float = 3.0,
    window: float = 0.5,
) -> list[Any]:
    """Pairs of samples of two vehicles within ``window`` wall s of each other, closer than
    ``horizontal`` m apart and ``vertical`` m in altitude."""
    found = []
    for (i, a), (j, b) in combinations(sorted(traces.items()), 2):
        k = 0
        for ta, (lat_a, lon_a, alt_a, _) in zip(a.stamps, a.track, strict=True):
            while k < len(b.stamps) and b.stamps[k] < ta - window:
                k += 1
            for tb, (lat_b, lon_b, alt_b, _) in zip(b.stamps[k:], b.track[k:], strict=True):
                if tb > ta + window:
                    break
                if (
                    abs(alt_a - alt_b) < vertical
                    and metres((lat_a, lon_a), (lat_b, lon_b)) < horizontal
                ):
                    found.append((i, j, alt_a, alt_b))
    return found
