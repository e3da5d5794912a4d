"""`companion profile import`: a fence drawn in QGroundControl (.plan), Google Earth (KML) or a
GIS (GeoJSON) becomes a profile's site fence, its origin and search area derived from it; and
every file that cannot be a fence is refused with its name and the fault."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pytest

from companion.cli import main
from companion.fence_from_profile import fence_for, profile_frame
from mdm_ground.site_files.fence_polygon import SiteFileError
from mdm_ground.site_files.formats import SUFFIXES
from mdm_ground.site_files.profile_from_fence import FenceImport, profile_with_fence
from mdm_ground.site_files.read_fence import READERS, read_fence_file
from mdm_profiles import load_profile

QGC_PLAN = Path(__file__).parents[1] / "data" / "qgc-duebendorf-east.plan"
"""A plan in the format QGroundControl saves (its Plan File Format): a five-vertex inclusion
fence over the east of the Duebendorf airfield, a takeoff item, no rally points."""
SQUARE = [(47.40, 8.64), (47.41, 8.64), (47.41, 8.65), (47.40, 8.65)]


def _plan_fence() -> list[tuple[float, float]]:
    plan = json.loads(QGC_PLAN.read_text())
    return [(a, b) for a, b in plan["geoFence"]["polygons"][0]["polygon"]]


def _import(tmp_path: Path, source: Path, *extra: str, base: str = "field-duebendorf") -> Path:
    out = tmp_path / "imported.yaml"
    assert main(["profile", "import", str(source), "--base", base, "--into", str(out), *extra]) == 0
    return out


def _plan(
    polygons: list[dict[str, Any]], circles: list[dict[str, Any]] | None = None, version: int = 2
) -> dict[str, Any]:
    return {
        "fileType": "Plan",
        "version": 1,
        "groundStation": "QGroundControl",
        "mission": {},
        "rallyPoints": {"points": [], "version": 2},
        "geoFence": {"circles": circles or [], "polygons": polygons, "version": version},
    }


def _polygon(ring: Sequence[tuple[object, object]], inclusion: bool = True) -> dict[str, Any]:
    return {"inclusion": inclusion, "polygon": [list(p) for p in ring], "version": 1}


def _geojson_polygon(ring: list[tuple[float, float]], **properties: Any) -> dict[str, Any]:
    coords = [[lon, lat] for lat, lon in [*ring, ring[0]]]
    return {
        "type": "Feature",
        "properties": properties,
        "geometry": {"type": "Polygon", "coordinates": [coords]},
    }


def _kml(*rings: list[tuple[float, float]]) -> str:
    placemarks = "".join(
        f"<Placemark><name>zone {k}</name><Polygon><outerBoundaryIs><LinearRing><coordinates>"
        + " ".join(f"{lon},{lat},0" for lat, lon in [*ring, ring[0]])
        + "</coordinates></LinearRing></outerBoundaryIs></Polygon></Placemark>"
        for k, ring in enumerate(rings)
    )
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n<kml xmlns="http://www.opengis.net/kml/2.2">'
        f"<Document><name>drawn</name>{placemarks}</Document></kml>\n"
    )


def test_a_qgc_plan_becomes_the_fence_and_its_bounding_rectangle_the_area(tmp_path: Path) -> None:
    profile = load_profile(_import(tmp_path, QGC_PLAN, "--targets", "fit"))
    assert profile.site is not None
    assert [(p.lat, p.lon) for p in profile.site.geofence] == _plan_fence()
    local = fence_for(profile).vertices
    # the origin is the south-west corner of the fence's bounds; the area reaches the far sides
    assert local[:, 0].min() == pytest.approx(0.0, abs=0.002)
    assert local[:, 1].min() == pytest.approx(0.0, abs=0.002)
    assert 0.0 <= profile.area.north - local[:, 0].max() <= 0.1
    assert 0.0 <= profile.area.east - local[:, 1].max() <= 0.1
    assert profile.origin.alt == load_profile("field-duebendorf").origin.alt


def test_margin_grows_the_area_by_the_same_metres_on_every_side(tmp_path: Path) -> None:
    plain = load_profile(_import(tmp_path, QGC_PLAN, "--targets", "fit"))
    wide = load_profile(_import(tmp_path, QGC_PLAN, "--targets", "fit", "--margin", "50"))
    local = fence_for(wide).vertices
    assert local[:, 0].min() == pytest.approx(50.0, abs=0.002)
    assert local[:, 1].min() == pytest.approx(50.0, abs=0.002)
    assert wide.area.north == pytest.approx(plain.area.north + 100.0, abs=0.11)
    assert wide.area.east == pytest.approx(plain.area.east + 100.0, abs=0.11)


def test_keep_area_replaces_only_the_fence(tmp_path: Path) -> None:
    base = load_profile("field-duebendorf")
    profile = load_profile(_import(tmp_path, QGC_PLAN, "--keep-area"))
    assert (profile.origin, profile.area, profile.targets) == (base.origin, base.area, base.targets)
    assert profile.site is not None
    assert [(p.lat, p.lon) for p in profile.site.geofence] == _plan_fence()


def test_keep_area_refuses_a_fence_far_from_the_area(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    zurich = [(47.37, 8.53), (47.38, 8.53), (47.38, 8.54), (47.37, 8.54)]
    drawn = tmp_path / "elsewhere.geojson"
    drawn.write_text(json.dumps(_geojson_polygon(zurich)))
    out = tmp_path / "p.yaml"
    argv = ["profile", "import", str(drawn), "--base", "field-duebendorf", "--into", str(out),
            "--keep-area"]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"{drawn}: the fence lies " in err
    assert "m from the profile's search area (--keep-area)" in err


def test_targets_keep_their_ground_position_by_default(tmp_path: Path) -> None:
    ring = [(47.3962, 8.6383), (47.4080, 8.6383), (47.4080, 8.6660), (47.3962, 8.6660)]
    drawn = tmp_path / "box.geojson"
    drawn.write_text(json.dumps(_geojson_polygon(ring)))
    base = load_profile("field-duebendorf")
    profile = load_profile(_import(tmp_path, drawn))
    assert profile.origin != base.origin
    old, new = profile_frame(base), profile_frame(profile)
    for before, after in zip(base.targets, profile.targets, strict=True):
        lat, lon, _ = old.to_geodetic(before.north, before.east, 0.0)
        ground = new.to_geodetic(after.north, after.east, 0.0)
        metres = math.dist(new.to_local(lat, lon, base.origin.alt)[:2], new.to_local(*ground)[:2])
        assert metres <= 0.08, (before, after)  # rounded to 0.1 m in each axis


def test_targets_fit_scales_them_into_the_new_area(tmp_path: Path) -> None:
    base = load_profile("field-duebendorf")
    profile = load_profile(_import(tmp_path, QGC_PLAN, "--targets", "fit"))
    for before, after in zip(base.targets, profile.targets, strict=True):
        assert after.north == pytest.approx(
            before.north / base.area.north * profile.area.north, abs=0.051
        )
        assert after.east == pytest.approx(
            before.east / base.area.east * profile.area.east, abs=0.051
        )


def test_targets_left_outside_the_new_area_are_refused_naming_the_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "p.yaml"
    argv = ["profile", "import", str(QGC_PLAN), "--base", "field-duebendorf", "--into", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert str(QGC_PLAN) in err
    assert "lies outside the area" in err
    assert "--targets ground" in err
    assert not out.exists()


def test_an_imported_fence_is_held_clockwise_from_the_files_first_vertex(tmp_path: Path) -> None:
    drawn = tmp_path / "ccw.kml"
    drawn.write_text(_kml([SQUARE[0], *reversed(SQUARE[1:])]))
    profile = load_profile(_import(tmp_path, drawn, "--targets", "fit"))
    assert profile.site is not None
    assert [(p.lat, p.lon) for p in profile.site.geofence] == SQUARE


def test_a_kml_polygon_from_google_earth_is_read_in_either_namespace(tmp_path: Path) -> None:
    for namespace in ("http://www.opengis.net/kml/2.2", "http://earth.google.com/kml/2.2"):
        drawn = tmp_path / "drawn.kml"
        drawn.write_text(_kml(SQUARE).replace("http://www.opengis.net/kml/2.2", namespace))
        assert read_fence_file(drawn).vertices == tuple(SQUARE)


def test_a_geojson_feature_a_bare_polygon_and_a_collection_are_read(tmp_path: Path) -> None:
    feature = _geojson_polygon(SQUARE)
    for name, data in [
        ("feature", feature),
        ("bare", feature["geometry"]),
        ("collection", {"type": "FeatureCollection", "features": [feature]}),
    ]:
        drawn = tmp_path / f"{name}.geojson"
        drawn.write_text(json.dumps(data))
        assert read_fence_file(drawn).vertices == tuple(SQUARE)


def test_of_several_polygons_the_one_marked_fence_is_taken(tmp_path: Path) -> None:
    bigger = [(47.39, 8.63), (47.42, 8.63), (47.42, 8.66), (47.39, 8.66)]
    drawn = tmp_path / "marked.geojson"
    drawn.write_text(
        json.dumps(
            {
                "type": "FeatureCollection",
                "features": [
                    _geojson_polygon(bigger, kind="search_area"),
                    _geojson_polygon(SQUARE, kind="fence"),
                ],
            }
        )
    )
    assert read_fence_file(drawn).vertices == tuple(SQUARE)


def test_a_vertex_repeated_at_once_is_merged(tmp_path: Path) -> None:
    drawn = tmp_path / "double-click.plan"
    drawn.write_text(
        json.dumps(_plan([_polygon([SQUARE[0], SQUARE[1], SQUARE[1], *SQUARE[2:], SQUARE[0]])]))
    )
    assert read_fence_file(drawn).vertices == tuple(SQUARE)


def test_an_unwritable_profile_is_refused_naming_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "no-such-dir" / "p.yaml"
    argv = ["profile", "import", str(QGC_PLAN), "--base", "field-duebendorf", "--into", str(out),
            "--targets", "fit"]  # fmt: skip
    assert main(argv) == 2
    assert f"companion: {out}: cannot be written: No such file or directory" in (
        capsys.readouterr().err
    )


def test_every_suffix_offered_has_a_reader() -> None:
    assert tuple(READERS) == SUFFIXES


BOWTIE = [(47.40, 8.64), (47.41, 8.65), (47.41, 8.64), (47.40, 8.65)]
CONCAVE = [(47.40, 8.64), (47.41, 8.64), (47.405, 8.645), (47.41, 8.65), (47.40, 8.65)]


@pytest.mark.parametrize(
    ("name", "content", "expected"),
    [
        ("exclusion.plan", _plan([_polygon(SQUARE, inclusion=False)]),
         "geoFence.polygons[0] is an exclusion zone"),
        ("circle.plan", _plan([], [{"circle": {"center": [47.4, 8.64], "radius": 300.0},
                                   "inclusion": True, "version": 1}]),
         "geoFence.circles[0] is a circular fence"),
        ("two.plan", _plan([_polygon(SQUARE), _polygon(SQUARE)]),
         "2 polygons (geoFence.polygons[0], geoFence.polygons[1])"),
        ("with-exclusion.plan", _plan([_polygon(SQUARE), _polygon(SQUARE, inclusion=False)]),
         "geoFence.polygons[1] is an exclusion zone"),
        ("old.plan", _plan([_polygon(SQUARE)], version=1), "geoFence version 1"),
        ("nofence.plan", {"fileType": "Plan", "mission": {}}, "the plan has no geoFence"),
        ("empty.plan", _plan([]), "no polygon found"),
        ("geojson.plan", _geojson_polygon(SQUARE), "not a QGroundControl plan (fileType None"),
        ("crossing.plan", _plan([_polygon(BOWTIE)]), "is not a simple polygon: Self-intersection"),
        ("concave.plan", _plan([_polygon(CONCAVE)]), "is not convex"),
        ("lat.plan", _plan([_polygon([(47.40, 8.64), (95.0, 8.64), (47.41, 8.65)])]),
         "geoFence.polygons[0] vertex 1: latitude 95, longitude 8.64 out of range"),
        ("text.plan", _plan([_polygon([(47.40, 8.64), ("47.41", 8.64), (47.41, 8.65)])]),
         "vertex 1: a coordinate must be a number, got '47.41'"),
        ("line.plan", _plan([_polygon([(47.40, 8.64), (47.41, 8.64), (47.40, 8.64)])]),
         "a fence needs at least 3 distinct vertices, got 2"),
        ("lon.geojson", _geojson_polygon([(47.40, 8.64), (47.41, 188.0), (47.41, 8.65)]),
         "latitude 47.41, longitude 188 out of range"),
        ("two.geojson", {"type": "FeatureCollection",
                         "features": [_geojson_polygon(SQUARE), _geojson_polygon(SQUARE)]},
         "2 polygons (features[0] geometry, features[1] geometry)"),
        ("multi.geojson", {"type": "MultiPolygon", "coordinates": [
            _geojson_polygon(SQUARE)["geometry"]["coordinates"]] * 2}, "2 polygons"),
        ("hole.geojson", {"type": "Polygon", "coordinates": [
            _geojson_polygon(SQUARE)["geometry"]["coordinates"][0]] * 2}, "has 2 rings"),
        ("points.geojson", {"type": "Point", "coordinates": [8.64, 47.4]},
         "no polygon found (it holds 1 feature(s) without a polygon)"),
        ("plan.geojson", _plan([_polygon(SQUARE)]), "(a QGroundControl plan: name it .plan)"),
        ("crossing.kml", _kml(BOWTIE), "placemark 0 (zone 0) is not a simple polygon"),
        ("two.kml", _kml(SQUARE, SQUARE), "2 polygons (placemark 0 (zone 0), placemark 1 (zone 1))"),
        ("html.kml", "<html><body>fence</body></html>", "not KML (the root element is <html>"),
        ("broken.kml", "<kml><Document>", "not KML (not XML"),
        ("zipped.kml", "PK\x03\x04", "a KMZ (zip) file"),
        ("fence.kmz", "PK\x03\x04", "a KMZ (zip) file"),
        ("fence.txt", "QGC WPL 110", "not a site file this reads (.plan, .kml, .geojson, .json)"),
        ("broken.geojson", "{not json", "not GeoJSON (not JSON"),
        ("letters.kml", _kml(SQUARE).replace("8.65,47.41", "8.65,abc"),
         "KML that cannot be read: Invalid coordinates"),
    ],
)  # fmt: skip
def test_files_that_are_no_fence_are_refused_naming_file_and_fault(
    tmp_path: Path, name: str, content: object, expected: str
) -> None:
    path = tmp_path / name
    path.write_text(content if isinstance(content, str) else json.dumps(content))
    with pytest.raises(SiteFileError) as refused:
        read_fence_file(path)
    message = str(refused.value)
    assert message.startswith(f"{path}: "), message
    assert expected in message, message


def test_a_refused_file_exits_2_with_its_reason_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    drawn = tmp_path / "bowtie.kml"
    drawn.write_text(_kml(BOWTIE))
    out = tmp_path / "p.yaml"
    argv = ["profile", "import", str(drawn), "--base", "field-duebendorf", "--into", str(out)]
    assert main(argv) == 2
    assert f"companion: {drawn}: placemark 0 (zone 0) is not a simple polygon" in (
        capsys.readouterr().err
    )
    assert not out.exists()


def test_import_without_base_needs_an_existing_profile(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "new.yaml"
    assert main(["profile", "import", str(QGC_PLAN), "--into", str(out)]) == 2
    assert f"--into {out}: no such profile; give --base" in capsys.readouterr().err


def test_a_fence_too_small_for_the_inset_is_refused(tmp_path: Path) -> None:
    tiny = [(47.4000, 8.6400), (47.4002, 8.6400), (47.4002, 8.6403), (47.4000, 8.6403)]
    drawn = tmp_path / "tiny.geojson"
    drawn.write_text(json.dumps(_geojson_polygon(tiny)))
    base = load_profile("field-duebendorf")
    with pytest.raises(SiteFileError) as refused:
        profile_with_fence(base, read_fence_file(drawn), str(drawn), FenceImport(targets="fit"))
    assert str(refused.value).startswith(f"{drawn}: the geofence is too small"), refused.value
    assert "site.fence_inset 20 m" in str(refused.value)
