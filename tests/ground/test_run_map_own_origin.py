"""A profile without ``site`` is flown in the vehicle's own frame, which starts where the vehicle
booted: the run map places its path at the origin the link reported (GPS_GLOBAL_ORIGIN), not
at the profile's default origin (47.397742, 8.545594). On stock ArduCopter SITL at its default
home (Canberra) the path lies there."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

from mdm_ground.run_map.geojson import run_geojson
from mdm_ground.run_map.tracks import read_tracks
from mdm_profiles import load_profile
from tests import sitl

CANBERRA = (-35.363261, 149.165230)  # ArduCopter SITL's default home (start-arducopter)


def _metres(a: tuple[float, float], b: tuple[float, float]) -> float:
    north = math.radians(b[0] - a[0]) * 6_371_000.0
    east = math.radians(b[1] - a[1]) * 6_371_000.0 * math.cos(math.radians(a[0]))
    return math.hypot(north, east)


def _paths(doc: dict[str, object]) -> list[list[float]]:
    features = doc["features"]
    assert isinstance(features, list)
    return [
        c
        for f in features
        if f["properties"]["kind"] == "path"
        for c in f["geometry"]["coordinates"]
    ]


def test_a_path_in_the_vehicles_own_frame_is_drawn_at_its_reported_origin(tmp_path: Path) -> None:
    own = (-35.0, 149.0)
    log = tmp_path / "mission-0.jsonl"
    log.write_text(
        "\n".join(
            json.dumps(r)
            for r in [
                {
                    "t": 1.0,
                    "event": "frame",
                    "source": "own",
                    "lat": own[0],
                    "lon": own[1],
                    "north": 0.0,
                    "east": 0.0,
                },
                {"t": 10.0, "event": "tick", "north": 0.0, "east": 0.0, "alt": 30.0},
                {"t": 20.0, "event": "tick", "north": 100.0, "east": 0.0, "alt": 30.0},
            ]
        )
        + "\n"
    )
    doc = run_geojson(load_profile("paper-fixed"), read_tracks(tmp_path, [0]))
    first, second = _paths(doc)
    assert first == [own[1], own[0]]
    assert abs(_metres(own, (second[1], second[0])) - 100.0) < 0.5
    assert second[1] > own[0]  # 100 m north of the origin


def test_a_profile_without_site_on_arducopter_sitl_maps_where_the_vehicle_flew(
    arducopter: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    inst = arducopter(speedup=5)
    out = tmp_path / "run"
    with (tmp_path / "companion.out").open("wb") as f:
        code = subprocess.run(
            [sys.executable, "-m", "companion.cli", "run", "--profile", "paper-fixed",
             "--vehicle", "0", "--system-id", str(inst.sysid), "--connect", inst.companion_url,
             "--duration", "20", "--sensor-source", "virtual", "--log-dir", str(out),
             "--land-wait", "300", "--flight-log-wait", "0"],
            stdout=f, stderr=subprocess.STDOUT, timeout=900, check=False,
            env=dict(os.environ, PYTHONUNBUFFERED="1"),
        ).returncode  # fmt: skip
    text = (tmp_path / "companion.out").read_text(errors="replace")
    assert code == 0, text[-3000:]
    path = _paths(json.loads((out / "map-0.geojson").read_text()))
    far = max(_metres(CANBERRA, (lat, lon)) for lon, lat in path)
    print(f"\n{len(path)} path points, the farthest {far:.0f} m from the SITL's home")
    assert len(path) >= 3
    assert far < 2000.0, f"path drawn {far:.0f} m from where the vehicle flew"
