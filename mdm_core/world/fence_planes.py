"""A field profile's fence as the search policy reads it: the half-planes of its convex polygon,
each moved ``site.fence_inset`` inwards. A waypoint lies inside where, for every half-plane
(n_north, n_east, offset), n_north * north + n_east * east >= offset (docs/model.md, "Search
near the fence")."""

from __future__ import annotations

import math

import pymap3d

from mdm_profiles import MissionProfile

HalfPlane = tuple[float, float, float]


def local_fence(profile: MissionProfile) -> list[tuple[float, float]]:
    """The fence's vertices in metres (north, east) of the profile's origin (as the companion's
    LocalFrame converts them); empty for a profile without ``site``."""
    if profile.site is None:
        return []
    o = profile.origin
    out = []
    for p in profile.site.geofence:
        north, east, _ = pymap3d.geodetic2ned(p.lat, p.lon, o.alt, o.lat, o.lon, o.alt)
        out.append((float(north), float(east)))
    return out


def inset_half_planes(vertices: list[tuple[float, float]], inset: float) -> tuple[HalfPlane, ...]:
    """Inward half-planes of a convex polygon moved ``inset`` metres in; ValueError for a
    polygon that is not convex (its half-planes would not describe it)."""
    turns = []
    n = len(vertices)
    for i in range(n):
        (an, ae), (bn, be), (cn, ce) = vertices[i], vertices[(i + 1) % n], vertices[(i + 2) % n]
        turns.append((bn - an) * (ce - be) - (be - ae) * (cn - bn))
    if not (all(t > 0 for t in turns) or all(t < 0 for t in turns)):
        raise ValueError("site.geofence must be a convex polygon (its vertices in order)")
    # the same orientation as companion.geofence.Geofence.inset: turn > 0 is one winding
    turn = 1.0 if turns[0] > 0 else -1.0
    planes = []
    for i in range(n):
        (an, ae), (bn, be) = vertices[i], vertices[(i + 1) % n]
        dn, de = bn - an, be - ae
        length = math.hypot(dn, de)
        nn, ne = -de / length * turn, dn / length * turn
        planes.append((nn, ne, nn * an + ne * ae + inset))
    return tuple(planes)


def fence_half_planes(profile: MissionProfile) -> tuple[HalfPlane, ...]:
    """The half-planes waypoints are drawn inside: the site fence moved ``site.fence_inset``
    inwards; none for a paper profile (no ``site``)."""
    if profile.site is None:
        return ()
    return inset_half_planes(local_fence(profile), profile.site.fence_inset)
