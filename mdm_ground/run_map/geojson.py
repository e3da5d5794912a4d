"""A run as a GeoJSON FeatureCollection (RFC 7946): [lon, lat] positions, closed polygons.

Every feature has a ``kind`` property (fence, search_area, path, detection, confirmation,
target) so QGIS and QGroundControl users can style by it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from companion.fence_from_profile import fence_for
from companion.link.local_frame import LocalFrame
from mdm_ground.run_map.tracks import Sample, VehicleTrack
from mdm_profiles import MissionProfile

_DIGITS = 7
"""Decimal places of a degree: about 1 cm, well below GPS error (RFC 7946 11.2)."""


def _lon_lat(frame: LocalFrame, north: float, east: float) -> list[float]:
    lat, lon, _ = frame.to_geodetic(north, east, 0.0)
    return [round(lon, _DIGITS), round(lat, _DIGITS)]


def _ring(frame: LocalFrame, vertices: np.ndarray) -> list[list[float]]:
    """A closed linear ring, counter-clockwise (the RFC's right-hand rule for exterior rings)."""
    ring = [_lon_lat(frame, float(n), float(e)) for n, e in vertices]
    # Shoelace on (lon, lat): positive area is counter-clockwise.
    area = sum(a[0] * b[1] - b[0] * a[1] for a, b in zip(ring, ring[1:] + ring[:1], strict=True))
    if area < 0:
        ring.reverse()
    return [*ring, ring[0]]


def _feature(geometry: dict[str, Any], **properties: Any) -> dict[str, Any]:
    return {"type": "Feature", "geometry": geometry, "properties": properties}


def _point(frame: LocalFrame, s: Sample, **properties: Any) -> dict[str, Any]:
    where = _lon_lat(frame, s.north, s.east)
    return _feature(
        {"type": "Point", "coordinates": where},
        t=s.t,
        north=round(s.north, 1),
        east=round(s.east, 1),
        **properties,
    )


def map_origin(profile: MissionProfile, tracks: list[VehicleTrack]) -> tuple[float, float]:
    """Where the map's frame starts: the profile's origin, unless the vehicles flew in their
    own frames (no ``site``): then the first one's origin, where the link said it was."""
    own = next((t.origin for t in tracks if t.origin is not None), None)
    return own if own is not None else (profile.origin.lat, profile.origin.lon)


def run_geojson(profile: MissionProfile, tracks: list[VehicleTrack]) -> dict[str, Any]:
    """The FeatureCollection of a run flown with ``profile``: the area, fence and targets
    placed at :func:`map_origin`, each vehicle's points at its own origin where it has one."""
    lat, lon = map_origin(profile, tracks)
    frame = LocalFrame(lat, lon, profile.origin.alt)
    a = profile.area
    box = np.array([[0.0, 0.0], [a.north, 0.0], [a.north, a.east], [0.0, a.east]])
    features = [
        _feature(
            {"type": "Polygon", "coordinates": [_ring(frame, fence_for(profile).vertices)]},
            kind="fence",
        ),
        _feature({"type": "Polygon", "coordinates": [_ring(frame, box)]}, kind="search_area"),
    ]
    moving = profile.target_motion is not None
    for k, t in enumerate(profile.targets):
        features.append(
            _point(
                frame,
                Sample(0.0, t.north, t.east),
                kind="target",
                target=k,
                false_target=t.false_target,
                appear=t.appear,
                position="start" if moving else "fixed",
            )
        )
    for track in tracks:
        v = track.vehicle
        where = frame if track.origin is None else LocalFrame(*track.origin, profile.origin.alt)
        if len(track.path) >= 2:
            line = [_lon_lat(where, s.north, s.east) for s in track.path]
            features.append(
                _feature(
                    {"type": "LineString", "coordinates": line},
                    kind="path",
                    vehicle=v,
                    samples=len(line),
                    t_first=track.path[0].t,
                    t_last=track.path[-1].t,
                    end=track.end_reason,
                )
            )
        for s, level in track.detections:
            features.append(_point(where, s, kind="detection", vehicle=v, level=level))
        for s in track.confirmations:
            features.append(_point(where, s, kind="confirmation", vehicle=v))
    # Only the members RFC 7946 defines: a reader owes nothing to foreign ones.
    return {"type": "FeatureCollection", "features": features}
