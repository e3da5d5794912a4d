"""The geofence a vehicle enforces besides the search area plus MDM_FENCE_MARG: the fence a
client uploaded (mission_type FENCE: inclusion/exclusion polygons and circles) and the
persona's parameter fences (ArduCopter FENCE_TYPE bit 0 FENCE_ALT_MAX, bit 1 FENCE_RADIUS about
home, bit 2 the polygons; PX4 GF_MAX_HOR_DIST / GF_MAX_VER_DIST from home). A breach fires the
persona's fence action (FENCE_ACTION / GF_ACTION), as the area fence does.

The uploaded items are turned into local-frame shapes once per upload; only a vehicle with a
fence of its own pays for the check.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from sim_vehicle_stub.mavlink import dialect as d

if TYPE_CHECKING:
    from sim_vehicle_stub.geo_frame import GeoFrame
    from sim_vehicle_stub.mission_store import MissionItem
    from sim_vehicle_stub.vehicle import Vehicle

Point = tuple[float, float]


@dataclass(frozen=True)
class Circle:
    north: float
    east: float
    radius: float

    def contains(self, n: float, e: float) -> bool:
        return math.hypot(n - self.north, e - self.east) <= self.radius


@dataclass(frozen=True)
class Polygon:
    vertices: tuple[Point, ...]

    def contains(self, n: float, e: float) -> bool:
        """Even-odd ray casting."""
        inside = False
        pts = self.vertices
        j = len(pts) - 1
        for i, (ni, ei) in enumerate(pts):
            nj, ej = pts[j]
            if (ei > e) != (ej > e) and n < (nj - ni) * (e - ei) / (ej - ei) + ni:
                inside = not inside
            j = i
        return inside


Shape = Circle | Polygon


@dataclass
class FenceShapes:
    """The uploaded fence in the profile's frame."""

    revision: int = -1
    inclusions: list[Shape] = field(default_factory=list)
    exclusions: list[Shape] = field(default_factory=list)

    @property
    def empty(self) -> bool:
        return not (self.inclusions or self.exclusions)


def shapes(items: list[MissionItem], geo: GeoFrame, revision: int) -> FenceShapes:
    """Group fence items into shapes: consecutive polygon vertices (param1 = the count) form a
    polygon; circles are one item (param1 = radius). Malformed groups are skipped."""
    out = FenceShapes(revision)
    k = 0
    while k < len(items):
        it = items[k]
        n, e, _ = geo.to_local(it.x * 1e-7, it.y * 1e-7, geo.alt)
        cmd = it.command
        if cmd in (d.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION, d.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION):
            radius = it.params[0]
            if math.isfinite(radius) and radius > 0:
                target = (
                    out.inclusions
                    if cmd == d.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION
                    else out.exclusions
                )
                target.append(Circle(n, e, radius))
            k += 1
            continue
        if cmd in (
            d.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION,
            d.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION,
        ):
            count = int(it.params[0]) if math.isfinite(it.params[0]) else 0
            group = items[k : k + max(count, 1)]
            if count >= 3 and len(group) == count and all(g.command == cmd for g in group):
                vertices = tuple(geo.to_local(g.x * 1e-7, g.y * 1e-7, geo.alt)[:2] for g in group)
                target = (
                    out.inclusions
                    if cmd == d.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
                    else out.exclusions
                )
                target.append(Polygon(vertices))
            k += max(count, 1)
            continue
        k += 1  # a return point, or an item that is no shape
    return out


def breach(v: Vehicle) -> str | None:
    """Which of the vehicle's own fences it is outside of (None: inside all, or none set)."""
    rules = v.limits.fence_rules
    if rules is None or not (rules.alt_max > 0 or rules.radius > 0 or v.plans.fence.items):
        return None
    f, i = v.fleet, v.index
    n, e, alt = float(f.pos[i, 0]), float(f.pos[i, 1]), float(f.alt[i])
    if rules.alt_max > 0 and alt > rules.alt_max:
        return "altitude"
    if rules.radius > 0 and math.hypot(n - v.home[0], e - v.home[1]) > rules.radius:
        return "radius"
    if not rules.polygons:
        return None
    store = v.plans.fence
    cache = v.fence_shapes
    if cache.revision != store.revision:
        cache = v.fence_shapes = shapes(store.items, v.geo, store.revision)
    if cache.empty:
        return None
    if any(s.contains(n, e) for s in cache.exclusions):
        return "exclusion zone"
    if cache.inclusions:
        inside = [s.contains(n, e) for s in cache.inclusions]
        if not (any(inside) if rules.union else all(inside)):
            return "inclusion zone"
    return None


@dataclass(frozen=True)
class FenceRules:
    """The persona's parameter fences now (0: off)."""

    alt_max: float
    radius: float
    polygons: bool
    """Whether the uploaded shapes are enforced."""
    union: bool
    """Inside any inclusion shape suffices (PX4), or inside all of them (ArduPilot)."""
