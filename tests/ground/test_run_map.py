"""The map after a live run: `companion fleet` (and each `companion run` in it) writes GeoJSON
(RFC 7946: [lon, lat], closed counter-clockwise rings; read by GDAL as QGIS reads it) whose
paths and confirmations are the mission logs', and a PNG."""

from __future__ import annotations

import itertools
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pymap3d
import pyogrio
import pytest

from companion.cli import main
from companion.telemetry import read_records
from mdm_core.world import Scenario
from mdm_ground.run_map.png import scale_bar_length
from mdm_profiles import load_profile
from tests.emulator_harness import free_udp_base
from tests.profile_files import levels, profile_with, sensors, write_profile_with

SEED = 4


def _changes(north: float, east: float) -> dict[str, Any]:
    """The run-map profile, its real target at (north, east)."""
    corners = [(47.39636, 8.63853), (47.40464, 8.63853), (47.40464, 8.65731), (47.39636, 8.65731)]
    return {
        "area": {"north": 1000.0, "east": 1500.0},
        "origin": {"lat": 47.3960, "lon": 8.6380, "alt": 440.0},
        "targets": [
            {"north": north, "east": east},
            {"north": 300.0, "east": 300.0, "false_target": True},
        ],
        "fleet": {"start": "periphery_even"},
        "sensors": sensors(400.0, 100.0),
        "sensor_source": {"kind": "virtual"},
        "policy": {"levels": levels(400.0, 200.0, 400.0)},
        "mission": {"duration": 150.0, "ts_cap": 150.0},
        "site": {"geofence": [{"lat": lat, "lon": lon} for lat, lon in corners]},
    }


def _profile(path: Path) -> Path:
    """The profile with its real target where vehicle 0 starts (start points do not depend on
    the targets): a confirmation on the map whatever the search does."""
    draft = profile_with("run-map-test", **_changes(0.0, 0.0))
    start, _ = Scenario.from_profile(draft).live_run(SEED, 2, draft.fleet.start)
    north, east = (round(float(x), 1) for x in start[0])
    return write_profile_with(path, "run-map-test", **_changes(north, east))


def _features(doc: dict[str, Any], kind: str) -> list[dict[str, Any]]:
    return [f for f in doc["features"] if f["properties"]["kind"] == kind]


def _lon_lat(north: float, east: float) -> tuple[float, float]:
    lat, lon, _ = pymap3d.ned2geodetic(north, east, 0.0, 47.3960, 8.6380, 440.0)
    return float(lon), float(lat)


def _signed_area(ring: list[list[float]]) -> float:
    return sum(a[0] * b[1] - b[0] * a[1] for a, b in itertools.pairwise(ring)) / 2


@pytest.mark.timeout(150)
@pytest.mark.usefixtures("fleet_processes")
def test_fleet_writes_a_geojson_that_matches_the_mission_logs_and_a_png(tmp_path: Path) -> None:
    path = _profile(tmp_path / "profile.yaml")
    out = tmp_path / "run"
    done = subprocess.run(
        [sys.executable, "-m", "companion.cli", "fleet", "--profile", str(path), "--out", str(out),
         "--speedup", "50", "--duration", "150", "--seed", str(SEED), "--quiet",
         "--base-port", str(free_udp_base(2))],
        capture_output=True, text=True, timeout=140, check=False,
        env=dict(os.environ, PYTHONUNBUFFERED="1"),
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    # on stderr: the fleet's stdout may be --json
    assert f"map: {out / 'map.geojson'} {out / 'map.png'}" in done.stderr
    doc = json.loads((out / "map.geojson").read_text())
    assert doc["type"] == "FeatureCollection"
    # GDAL's GeoJSON driver (what QGIS opens it with) reads every feature, in WGS84, lon/lat
    info = pyogrio.read_info(out / "map.geojson")
    assert (info["driver"], info["crs"]) == ("GeoJSON", "EPSG:4326")
    assert info["features"] == len(doc["features"])
    west, south, east, north = info["total_bounds"]
    assert 8.63 < west < east < 8.66
    assert 47.39 < south < north < 47.41
    for f in doc["features"]:
        assert f["type"] == "Feature"
        assert set(f) == {"type", "geometry", "properties"}
    (fence,) = _features(doc, "fence")
    (area,) = _features(doc, "search_area")
    for polygon in (fence, area):
        assert polygon["geometry"]["type"] == "Polygon"
        (ring,) = polygon["geometry"]["coordinates"]
        assert len(ring) >= 4
        assert ring[0] == ring[-1], "ring not closed"
        assert _signed_area(ring) > 0, "exterior ring not counter-clockwise"
    # [lon, lat]: the profile's fence corners come back in that order (lon ~8.6, lat ~47.4)
    corners = {(round(lon, 5), round(lat, 5)) for lon, lat in fence["geometry"]["coordinates"][0]}
    site = load_profile(path).site
    assert site is not None
    assert corners == {(round(p.lon, 5), round(p.lat, 5)) for p in site.geofence}
    targets = _features(doc, "target")
    assert [t["properties"]["false_target"] for t in targets] == [False, True]
    assert targets[1]["geometry"]["coordinates"] == pytest.approx(_lon_lat(300.0, 300.0), abs=1e-7)

    paths = {f["properties"]["vehicle"]: f for f in _features(doc, "path")}
    assert sorted(paths) == [0, 1]
    confirmations = _features(doc, "confirmation")
    assert confirmations, "the run confirmed nothing to put on the map"
    logged_confirmations = []
    for i in (0, 1):
        records = read_records(out / f"mission-{i}.jsonl")
        ticks = [r for r in records if r["event"] == "tick"]
        line = paths[i]["geometry"]["coordinates"]
        assert paths[i]["geometry"]["type"] == "LineString"
        assert len(line) == len(ticks) >= 2
        for (lon, lat), r in zip(line, ticks, strict=True):
            assert (lon, lat) == pytest.approx(_lon_lat(r["north"], r["east"]), abs=2e-7)
        logged_confirmations += [
            (i, r["t"], r["north"], r["east"]) for r in records if r["event"] == "confirmation"
        ]
    mapped = [
        (
            f["properties"]["vehicle"],
            f["properties"]["t"],
            f["properties"]["north"],
            f["properties"]["east"],
        )
        for f in confirmations
    ]
    assert len(mapped) == len(logged_confirmations)
    for got, logged in zip(sorted(mapped), sorted(logged_confirmations), strict=True):
        assert got == pytest.approx(logged, abs=0.05)
    for f in confirmations:
        p = f["properties"]
        assert f["geometry"]["coordinates"] == pytest.approx(
            _lon_lat(p["north"], p["east"]), abs=2e-7
        )
    assert (out / "map.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the fleet's map is the run's only one: its companions (run --no-map) draw none of their own
    assert sorted(p.name for p in out.glob("map*")) == ["map.geojson", "map.png"]
    # `companion map` redraws the same map from the same logs
    fleet_map = (out / "map.geojson").read_text()
    (out / "map.geojson").unlink()
    assert main(["map", "--profile", str(path), "--log-dir", str(out)]) == 0
    assert (out / "map.geojson").read_text() == fleet_map


def test_companion_map_without_mission_logs_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["map", "--profile", "paper-fixed", "--log-dir", str(tmp_path)]) == 2
    assert f"--log-dir {tmp_path}: no mission-I.jsonl in it" in capsys.readouterr().err


@pytest.mark.parametrize(("span", "bar"), [(2200.0, 200.0), (1000.0, 200.0), (12000.0, 2000.0),
                                           (90.0, 10.0), (26000.0, 5000.0)])  # fmt: skip
def test_scale_bar_is_a_round_length_near_a_fifth_of_the_map(span: float, bar: float) -> None:
    assert scale_bar_length(span) == bar
