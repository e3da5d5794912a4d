"""The one inclusion polygon a site file holds, checked where it enters: numbers, ranges, a
simple and convex ring (shapely); and the choice among a file's polygons."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from shapely.geometry import Polygon
from shapely.validation import explain_validity

from mdm_ground.errors import GroundError

CONVEX_TOLERANCE = 1e-9
"""Relative area by which a polygon may fall short of its convex hull and still count as
convex (rounding of the vertices' last digits)."""


class SiteFileError(GroundError, ValueError):
    """A site file (QGC .plan, KML, GeoJSON) or a profile export that cannot be used; the
    message names the file and what is wrong in it."""


@dataclass(frozen=True)
class Candidate:
    """A polygon as found in a file, before checks: where it is, whether it is an inclusion
    zone, whether the file marks it as the fence, and its (lat, lon) ring as written."""

    where: str
    ring: Sequence[Sequence[object]]
    inclusion: bool = True
    marked_fence: bool = False


@dataclass(frozen=True)
class FencePolygon:
    """A checked inclusion fence: (lat, lon) vertices in degrees, in the file's order, the
    closing vertex of a closed ring and repeats of the vertex before dropped."""

    vertices: tuple[tuple[float, float], ...]


def _number(source: str, where: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise SiteFileError(f"{source}: {where}: a coordinate must be a number, got {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise SiteFileError(f"{source}: {where}: a coordinate must be finite, got {value!r}")
    return number


def checked_fence(source: str, candidate: Candidate) -> FencePolygon:
    """``candidate`` as a fence, or :class:`SiteFileError` naming ``source``, the polygon and
    the fault: an exclusion zone, a vertex that is not a number or out of range, fewer than 3
    vertices, a ring that crosses or touches itself, a concave ring."""
    where = candidate.where
    if not candidate.inclusion:
        raise SiteFileError(
            f"{source}: {where} is an exclusion zone: the companion keeps one "
            "inclusion polygon as the fence (remove it, or make it inclusion)"
        )
    points: list[tuple[float, float]] = []
    for k, vertex in enumerate(candidate.ring):
        at = f"{where} vertex {k}"
        if len(vertex) < 2:
            raise SiteFileError(f"{source}: {at}: needs latitude and longitude, got {vertex!r}")
        lat, lon = _number(source, at, vertex[0]), _number(source, at, vertex[1])
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
            raise SiteFileError(
                f"{source}: {at}: latitude {lat:g}, longitude {lon:g} out of "
                "range (-90..90, -180..180)"
            )
        points.append((lat, lon))
    # a closed ring's last vertex, and a vertex repeated at once (a double click), add nothing
    points = [p for k, p in enumerate(points) if k == 0 or p != points[k - 1]]
    while len(points) > 1 and points[-1] == points[0]:
        points.pop()
    if len(set(points)) < 3:
        raise SiteFileError(
            f"{source}: {where}: a fence needs at least 3 distinct vertices, got {len(set(points))}"
        )
    shape = Polygon([(lon, lat) for lat, lon in points])
    if not shape.is_valid:
        raise SiteFileError(
            f"{source}: {where} is not a simple polygon: {explain_validity(shape)} (lon lat)"
        )
    hull = shape.convex_hull.area
    if shape.area < hull * (1.0 - CONVEX_TOLERANCE):
        raise SiteFileError(
            f"{source}: {where} is not convex ({shape.area / hull:.1%} of its "
            "convex hull): the companion moves the fence inwards by "
            "site.fence_inset, which needs a convex polygon"
        )
    return FencePolygon(tuple(points))


def pick_fence(source: str, candidates: Sequence[Candidate], ignored: str = "") -> FencePolygon:
    """The file's fence: its only polygon, or the only one it marks as the fence (an export of
    `companion profile export` marks it beside the search area); else :class:`SiteFileError`.
    ``ignored`` says what else the file held, for the message of a file without polygons."""
    if not candidates:
        extra = f" (it holds {ignored})" if ignored else ""
        raise SiteFileError(f"{source}: no polygon found{extra}: draw the fence as a polygon")
    for c in candidates:
        if not c.inclusion:
            checked_fence(source, c)  # refuses it, naming it
    marked = [c for c in candidates if c.marked_fence]
    if len(candidates) > 1 and len(marked) != 1:
        listed = ", ".join(c.where for c in candidates)
        raise SiteFileError(
            f"{source}: {len(candidates)} polygons ({listed}): the fence must be "
            "the only one, or the only one marked kind=fence"
        )
    return checked_fence(source, marked[0] if len(candidates) > 1 else candidates[0])
