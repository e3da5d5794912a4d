"""`companion profile export`: a profile's fence, search area, start points and targets as a
QGroundControl plan, KML and GeoJSON; each read back by GDAL (pyogrio) where it reads the
format, and each round trip through `companion profile import` giving the same fence."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pyogrio
import pytest
import shapely

from companion.cli import main
from companion.fence_from_profile import guidance_fence, profile_frame
from companion.mission.start_point import start_point
from mdm_profiles import MissionProfile, load_profile

QGC_PLAN = Path(__file__).parents[1] / "data" / "qgc-duebendorf-east.plan"


def _export(profile: str, *flags: str) -> None:
    assert main(["profile", "export", profile, *flags]) == 0


def _fence_metres(a: MissionProfile, b: MissionProfile) -> float:
    """The largest distance from a vertex of ``a``'s fence to the nearest vertex of ``b``'s (in
    ``a``'s frame; the fences may start at another vertex or run the other way round)."""
    assert a.site is not None
    assert b.site is not None
    frame = profile_frame(a)
    mine = [frame.to_local(p.lat, p.lon, a.origin.alt)[:2] for p in a.site.geofence]
    theirs = [frame.to_local(p.lat, p.lon, a.origin.alt)[:2] for p in b.site.geofence]
    assert len(mine) == len(theirs)
    return max(min(math.dist(m, t) for t in theirs) for m in mine)


@pytest.mark.parametrize("kind", ["plan", "kml", "geojson"])
def test_export_then_import_gives_the_same_fence(tmp_path: Path, kind: str) -> None:
    profile = tmp_path / "east.yaml"
    assert main(["profile", "import", str(QGC_PLAN), "--base", "field-duebendorf",
                 "--into", str(profile), "--targets", "fit"]) == 0  # fmt: skip
    exported = tmp_path / f"east.{kind}"
    _export(str(profile), f"--{kind}", str(exported))
    again = tmp_path / "again.yaml"
    assert main(["profile", "import", str(exported), "--base", str(profile), "--into",
                 str(again), "--targets", "frame"]) == 0  # fmt: skip
    before, after = load_profile(profile), load_profile(again)
    assert _fence_metres(before, after) <= 0.1
    assert after.site == before.site  # the same vertices, clockwise from the same one
    assert after.area == before.area
    assert (
        math.dist((after.origin.lat, after.origin.lon), (before.origin.lat, before.origin.lon))
        < 1e-8
    )


def test_the_plan_keeps_a_clockwise_fence_vertex_for_vertex(tmp_path: Path) -> None:
    plan = tmp_path / "d.plan"
    _export("field-duebendorf", "--plan", str(plan))
    data = json.loads(plan.read_text())
    profile = load_profile("field-duebendorf")
    assert profile.site is not None
    (polygon,) = data["geoFence"]["polygons"]
    assert polygon["inclusion"] is True
    assert [tuple(p) for p in polygon["polygon"]] == [(p.lat, p.lon) for p in profile.site.geofence]
    # what QGroundControl's loader requires of a plan (PlanMasterController, GeoFenceController)
    assert (data["fileType"], data["version"], data["geoFence"]["version"]) == ("Plan", 1, 2)
    assert isinstance(data["groundStation"], str)
    assert all(isinstance(data[k], dict) for k in ("mission", "geoFence", "rallyPoints"))
    assert data["geoFence"]["circles"] == []
    assert data["mission"]["items"] == []
    assert data["rallyPoints"]["points"] == []
    o = profile.origin
    assert data["mission"]["plannedHomePosition"] == [o.lat, o.lon, o.alt]
    assert data["mission"]["firmwareType"] == 3  # MAV_AUTOPILOT_ARDUPILOTMEGA


def test_a_counter_clockwise_fence_is_written_clockwise_to_the_plan(tmp_path: Path) -> None:
    profile = load_profile("field-duebendorf")
    assert profile.site is not None
    ring = [p.model_dump() for p in profile.site.geofence]
    ccw = tmp_path / "ccw.yaml"
    data = profile.model_dump(mode="json")
    data["site"]["geofence"] = [ring[0], *reversed(ring[1:])]
    ccw.write_text(json.dumps(data))  # JSON is YAML
    plan = tmp_path / "ccw.plan"
    _export(str(ccw), "--plan", str(plan), "--firmware", "px4")
    written = json.loads(plan.read_text())
    assert [tuple(p) for p in written["geoFence"]["polygons"][0]["polygon"]] == [
        (p["lat"], p["lon"]) for p in ring
    ]
    assert written["mission"]["firmwareType"] == 12  # MAV_AUTOPILOT_PX4


@pytest.mark.parametrize("kind", ["kml", "geojson"])
def test_gdal_reads_the_fence_area_starts_and_targets_where_they_are(
    tmp_path: Path, kind: str
) -> None:
    path = tmp_path / f"d.{kind}"
    seed = 7
    _export("field-duebendorf", f"--{kind}", str(path), "--seed", str(seed))
    profile = load_profile("field-duebendorf")
    frame = profile_frame(profile)
    _, table = pyogrio.read_arrow(path)
    kinds = [str(k) for k in table.column("kind").to_pylist()]
    vehicles = profile.fleet.vehicles
    assert kinds == ["fence", "search_area"] + ["start"] * vehicles + ["target"] * len(
        profile.targets
    )
    shapes = shapely.from_wkb(table.column("wkb_geometry").to_pylist())

    def local(point: shapely.Point) -> tuple[float, float]:
        n, e, _ = frame.to_local(point.y, point.x, profile.origin.alt)
        return n, e

    assert profile.site is not None
    fence = [(p.lon, p.lat) for p in profile.site.geofence]
    assert shapes[0].exterior.is_ccw  # RFC 7946 and KML: outer rings counter-clockwise
    assert shapely.Polygon(fence).equals(shapes[0])
    corners = [local(shapely.Point(c)) for c in shapes[1].exterior.coords[:-1]]
    a = profile.area
    expected = [(0.0, 0.0), (0.0, a.east), (a.north, a.east), (a.north, 0.0)]
    assert max(math.dist(c, x) for c, x in zip(corners, expected, strict=True)) < 0.01
    inner = guidance_fence(profile)
    for v, shape in enumerate(shapes[2 : 2 + vehicles]):
        assert math.dist(local(shape), start_point(profile, seed, v, inner)) < 0.01
    for t, shape in zip(profile.targets, shapes[2 + vehicles :], strict=True):
        assert math.dist(local(shape), (t.north, t.east)) < 0.01
    false_flags = [str(f).lower() for f in table.column("false_target").to_pylist()[2 + vehicles :]]
    assert false_flags == [str(t.false_target).lower() for t in profile.targets]


def test_an_unwritable_output_is_refused_naming_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "no-such-dir" / "d.kml"
    assert main(["profile", "export", "field-duebendorf", "--kml", str(out)]) == 2
    assert f"companion: {out}: cannot be written: No such file or directory" in (
        capsys.readouterr().err
    )


def test_export_needs_an_output(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["profile", "export", "field-duebendorf"]) == 2
    assert "give --plan, --kml and/or --geojson" in capsys.readouterr().err
