"""KML site files (fastkml): the fence is the file's one Polygon, or the one whose placemark
has ``kind`` = ``fence`` in its ExtendedData; a written file holds the fence, the search area,
the start points and the targets, for Google Earth, QGIS or any KML reader."""

from __future__ import annotations

from pathlib import Path

import pygeoif
from fastkml import KML, Data, Document, ExtendedData, Placemark, config
from fastkml.styles import LineStyle, PolyStyle, Style, StyleUrl
from fastkml.utils import find_all

from mdm_ground.site_files.fence_polygon import Candidate, FencePolygon, SiteFileError, pick_fence
from mdm_ground.site_files.site_layers import LatLon, SiteLayers, counter_clockwise

_POLYGONS = (pygeoif.Polygon, pygeoif.MultiPolygon, pygeoif.GeometryCollection)


def _kind(placemark: Placemark) -> str | None:
    data = placemark.extended_data
    for item in data.elements if data is not None else []:
        if isinstance(item, Data) and item.name == "kind":
            return item.value
    return None


def _candidates(where: str, geometry: object, marked: bool, source: str) -> list[Candidate]:
    if isinstance(geometry, pygeoif.Polygon):
        if list(geometry.interiors):
            raise SiteFileError(
                f"{source}: {where} has inner boundaries: a fence is one outer ring, without holes"
            )
        ring = [(p[1], p[0]) for p in geometry.exterior.coords]
        return [Candidate(where, ring, marked_fence=marked)]
    if isinstance(geometry, pygeoif.MultiPolygon | pygeoif.GeometryCollection):
        return [
            c
            for k, part in enumerate(geometry.geoms)
            for c in _candidates(f"{where} part {k}", part, marked, source)
        ]
    return []


def _root_namespace(source: str, raw: bytes) -> str:
    """The namespace of the file's root element, which must be <kml> (KML 2.2, or Google's
    older namespace)."""
    try:
        root = config.etree.fromstring(raw)
    except Exception as exc:  # lxml's and ElementTree's parse errors share no base class
        raise SiteFileError(f"{source}: not KML (not XML: {exc})") from exc
    tag = str(root.tag)
    namespace, _, name = tag.rpartition("}")
    if name != "kml":
        raise SiteFileError(f"{source}: not KML (the root element is <{name}>, not <kml>)")
    return f"{namespace}}}" if namespace else ""


def read_kml(path: Path) -> FencePolygon:
    """The fence of a KML file (Google Earth, Mission Planner, QGIS): placemarks' Polygons,
    also inside MultiGeometry; points and lines are not read. KMZ is refused (unzip it)."""
    source = str(path)
    raw = path.read_bytes()
    if raw.startswith(b"PK"):
        raise SiteFileError(f"{source}: a KMZ (zip) file: unzip it and import its doc.kml")
    ns = _root_namespace(source, raw)
    try:
        kml = KML.parse(path, ns=ns, strict=True, validate=False)
    except Exception as exc:  # fastkml raises ValueError, TypeError or its own KMLParseError
        raise SiteFileError(f"{source}: KML that cannot be read: {str(exc)[:300]}") from exc
    candidates: list[Candidate] = []
    others = 0
    for k, placemark in enumerate(find_all(kml, of_type=Placemark)):
        assert isinstance(placemark, Placemark)
        where = f"placemark {k} ({placemark.name or 'no name'})"
        found = _candidates(where, placemark.geometry, _kind(placemark) == "fence", source)
        candidates += found
        others += 0 if found else 1
    return pick_fence(source, candidates, f"{others} placemark(s) without a polygon")


def _polygon(ring: tuple[LatLon, ...]) -> pygeoif.Polygon:
    """Counter-clockwise, closed: KML's outer boundary."""
    points = [(lon, lat) for lat, lon in counter_clockwise(ring)]
    return pygeoif.Polygon([*points, points[0]])


def _data(**values: object) -> ExtendedData:
    return ExtendedData(elements=[Data(name=k, value=str(v)) for k, v in values.items()])


def kml_document(layers: SiteLayers) -> KML:
    """The profile's layers as one KML document: outlines (fence red, search area yellow), a
    point per start and per target, every placemark with its ``kind`` in ExtendedData."""
    styles = [
        Style(id="fence", styles=[LineStyle(color="ff0000ff", width=3), PolyStyle(fill=False)]),
        Style(
            id="search_area", styles=[LineStyle(color="ff00ffff", width=2), PolyStyle(fill=False)]
        ),
    ]
    features = [
        Placemark(
            name="fence",
            style_url=StyleUrl(url="#fence"),
            extended_data=_data(kind="fence"),
            geometry=_polygon(layers.fence),
        ),
        Placemark(
            name="search area",
            style_url=StyleUrl(url="#search_area"),
            extended_data=_data(kind="search_area"),
            geometry=_polygon(layers.area),
        ),
    ]
    for s in layers.starts:
        features.append(
            Placemark(
                name=f"start {s.vehicle}",
                geometry=pygeoif.Point(s.lon, s.lat),
                extended_data=_data(
                    kind="start", vehicle=s.vehicle, altitude=s.altitude, seed=layers.seed
                ),
            )
        )
    for t in layers.targets:
        label = "false target" if t.false_target else "target"
        features.append(
            Placemark(
                name=f"{label} {t.index}",
                geometry=pygeoif.Point(t.lon, t.lat),
                extended_data=_data(
                    kind="target", target=t.index, false_target=t.false_target, appear=t.appear
                ),
            )
        )
    return KML(features=[Document(name=layers.name, styles=styles, features=features)])


def write_kml(layers: SiteLayers, path: Path) -> None:
    """:func:`kml_document` as a file."""
    text = kml_document(layers).to_string(prettyprint=True)
    path.write_text(f'<?xml version="1.0" encoding="UTF-8"?>\n{text}', encoding="utf-8")
