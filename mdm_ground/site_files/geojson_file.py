"""GeoJSON (RFC 7946) site files: the fence is the file's one Polygon, or the one whose feature
says ``kind: fence``; a written file holds the fence, the search area, the start points and the
targets, each feature with a ``kind`` as in the run map (docs/companion.md, "Run map")."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from mdm_ground.site_files.fence_polygon import Candidate, FencePolygon, SiteFileError, pick_fence
from mdm_ground.site_files.site_layers import LatLon, SiteLayers, counter_clockwise


def _polygons(source: str, where: str, geometry: object, marked: bool) -> list[Candidate]:
    """The polygons of one geometry (a MultiPolygon or a GeometryCollection gives several)."""
    if not isinstance(geometry, dict):
        return []
    kind = geometry.get("type")
    if kind == "GeometryCollection":
        parts = geometry.get("geometries")
        if not isinstance(parts, list):
            raise SiteFileError(f"{source}: {where}.geometries must be a list")
        return [
            c
            for k, g in enumerate(parts)
            for c in _polygons(source, f"{where}.geometries[{k}]", g, marked)
        ]
    if kind not in ("Polygon", "MultiPolygon"):
        return []
    coordinates = geometry.get("coordinates")
    rings_of = [coordinates] if kind == "Polygon" else coordinates
    if not isinstance(rings_of, list) or not all(isinstance(r, list) for r in rings_of):
        raise SiteFileError(f"{source}: {where}.coordinates: not a list of linear rings")
    found = []
    for k, rings in enumerate(rings_of):
        at = where if kind == "Polygon" else f"{where} polygon {k}"
        if len(rings) != 1:
            raise SiteFileError(
                f"{source}: {at} has {len(rings)} rings: a fence is one outer ring, without holes"
            )
        ring = rings[0]
        if not isinstance(ring, list) or not all(isinstance(p, list) and len(p) >= 2 for p in ring):
            raise SiteFileError(f"{source}: {at}: positions must be [longitude, latitude]")
        found.append(Candidate(at, [(p[1], p[0]) for p in ring], marked_fence=marked))
    return found


def read_geojson(path: Path) -> FencePolygon:
    """The fence of a GeoJSON file: a FeatureCollection, a Feature or a bare geometry. Points
    and lines are not read; several polygons, holes, and positions out of range are refused."""
    source = str(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise SiteFileError(f"{source}: not GeoJSON (not JSON: {exc})") from exc
    kind = data.get("type") if isinstance(data, dict) else None
    if kind == "FeatureCollection":
        features = data.get("features")
        if not isinstance(features, list):
            raise SiteFileError(f"{source}: features must be a list")
        items = [(f"features[{k}]", f) for k, f in enumerate(features)]
    elif kind == "Feature":
        items = [("the feature", data)]
    elif isinstance(kind, str) and kind in _GEOMETRIES:
        items = [("the geometry", {"type": "Feature", "geometry": data, "properties": {}})]
    else:
        hint = (
            " (a QGroundControl plan: name it .plan)"
            if isinstance(data, dict) and data.get("fileType") == "Plan"
            else ""
        )
        raise SiteFileError(
            f"{source}: not GeoJSON: no FeatureCollection, Feature or geometry "
            f"'type' at the top (got {kind!r}){hint}"
        )
    candidates: list[Candidate] = []
    others = 0
    for where, feature in items:
        if not isinstance(feature, dict) or feature.get("type") != "Feature":
            raise SiteFileError(f"{source}: {where} is not a Feature")
        properties = feature.get("properties") or {}
        marked = isinstance(properties, dict) and properties.get("kind") == "fence"
        found = _polygons(source, f"{where} geometry", feature.get("geometry"), marked)
        candidates += found
        others += 0 if found else 1
    return pick_fence(source, candidates, f"{others} feature(s) without a polygon")


_GEOMETRIES = {
    "Point",
    "MultiPoint",
    "LineString",
    "MultiLineString",
    "Polygon",
    "MultiPolygon",
    "GeometryCollection",
}


def _ring(ring: tuple[LatLon, ...]) -> list[list[float]]:
    """A closed, counter-clockwise [lon, lat] ring (RFC 7946's exterior rings)."""
    out = [[lon, lat] for lat, lon in counter_clockwise(ring)]
    return [*out, out[0]]


def _feature(geometry: dict[str, Any], **properties: Any) -> dict[str, Any]:
    return {"type": "Feature", "geometry": geometry, "properties": properties}


def geojson_document(layers: SiteLayers) -> dict[str, Any]:
    """The profile's layers as one FeatureCollection."""
    features = [
        _feature(
            {"type": "Polygon", "coordinates": [_ring(layers.fence)]},
            kind="fence",
            name=f"{layers.name} fence",
        ),
        _feature(
            {"type": "Polygon", "coordinates": [_ring(layers.area)]},
            kind="search_area",
            name=f"{layers.name} search area",
        ),
    ]
    for s in layers.starts:
        features.append(
            _feature(
                {"type": "Point", "coordinates": [s.lon, s.lat]},
                kind="start",
                vehicle=s.vehicle,
                altitude=s.altitude,
                seed=layers.seed,
            )
        )
    for t in layers.targets:
        features.append(
            _feature(
                {"type": "Point", "coordinates": [t.lon, t.lat]},
                kind="target",
                target=t.index,
                false_target=t.false_target,
                appear=t.appear,
            )
        )
    return {"type": "FeatureCollection", "features": features}


def write_geojson(layers: SiteLayers, path: Path) -> None:
    """:func:`geojson_document` as a file."""
    path.write_text(json.dumps(geojson_document(layers), indent=1) + "\n", encoding="utf-8")
