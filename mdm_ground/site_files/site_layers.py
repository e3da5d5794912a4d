"""What an export shows of a profile, in WGS84: the fence, the search area, the origin, each
vehicle's start point for a seed and the (rehearsal) targets."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from companion.fence_from_profile import guidance_fence, profile_frame
from companion.mission.start_point import start_point
from mdm_profiles import MissionProfile

LatLon = tuple[float, float]
DIGITS = 8
"""Decimal places of a degree for converted points (area corners, starts, targets): about 1 mm.
The fence is written as the profile holds it."""


@dataclass(frozen=True)
class StartMark:
    """Where ``vehicle`` starts its search (after its transit), at ``altitude`` m above home."""

    vehicle: int
    lat: float
    lon: float
    altitude: float


@dataclass(frozen=True)
class TargetMark:
    """Target ``index`` of the profile: rehearsal markers in a field profile."""

    index: int
    lat: float
    lon: float
    false_target: bool
    appear: float


@dataclass(frozen=True)
class SiteLayers:
    """A profile's geometry as a ground station or a GIS shows it (degrees, metres AMSL)."""

    name: str
    fence: tuple[LatLon, ...]
    """``site.geofence`` as written in the profile, else the search area's rectangle."""
    area: tuple[LatLon, ...]
    """The search area's corners: origin (south-west), north-west, north-east, south-east."""
    home: tuple[float, float, float]
    """The profile's origin: lat, lon, alt AMSL."""
    speed: float
    starts: tuple[StartMark, ...]
    targets: tuple[TargetMark, ...]
    seed: int


def site_layers(profile: MissionProfile, seed: int) -> SiteLayers:
    """``profile``'s layers, with the start points the companions draw for ``seed`` (the
    `companion run --seed`), clamped into the guidance fence as in flight."""
    frame = profile_frame(profile)

    def geo(north: float, east: float) -> LatLon:
        lat, lon, _ = frame.to_geodetic(north, east, 0.0)
        return round(lat, DIGITS), round(lon, DIGITS)

    a = profile.area
    area = (geo(0.0, 0.0), geo(a.north, 0.0), geo(a.north, a.east), geo(0.0, a.east))
    site = profile.site
    fence = area if site is None else tuple((p.lat, p.lon) for p in site.geofence)
    inner = guidance_fence(profile)
    fleet = profile.fleet
    starts = []
    for v in range(fleet.vehicles):
        lat, lon = geo(*start_point(profile, seed, v, inner))
        starts.append(StartMark(v, lat, lon, fleet.altitude + v * fleet.altitude_step))
    targets = tuple(
        TargetMark(k, *geo(t.north, t.east), t.false_target, t.appear)
        for k, t in enumerate(profile.targets)
    )
    o = profile.origin
    return SiteLayers(
        profile.name, fence, area, (o.lat, o.lon, o.alt), fleet.speed, tuple(starts), targets, seed
    )


def _turn(ring: Sequence[LatLon]) -> float:
    """Twice the signed area on (lon, lat): positive for a counter-clockwise ring on a map."""
    pairs = zip(ring, [*ring[1:], ring[0]], strict=True)
    return sum(a[1] * b[0] - b[1] * a[0] for a, b in pairs)


def clockwise(ring: Sequence[LatLon]) -> list[LatLon]:
    """``ring`` in clockwise order on a map (QGC's plan format), the same start vertex."""
    return list(ring) if _turn(ring) < 0 else [ring[0], *reversed(ring[1:])]


def counter_clockwise(ring: Sequence[LatLon]) -> list[LatLon]:
    """``ring`` counter-clockwise (RFC 7946's and KML's outer rings), the same start vertex."""
    return list(ring) if _turn(ring) > 0 else [ring[0], *reversed(ring[1:])]
