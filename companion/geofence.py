"""A polygon geofence in the local (north, east) frame: containment and the nearest inside point."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


class Geofence:
    """A simple polygon (vertices in order, metres north/east of the profile origin).

    The guidance asks twice per setpoint; a fence has a handful of edges, so the geometry runs
    on Python floats over edges prepared once (numpy's per-call overhead was most of a
    companion's decision time). Same arithmetic as the array form, result for result.
    """

    def __init__(self, vertices: FloatArray) -> None:
        v = np.asarray(vertices, dtype=float)
        if v.ndim != 2 or v.shape[1] != 2 or len(v) < 3:
            raise ValueError(f"a geofence needs >= 3 (north, east) vertices, got shape {v.shape}")
        self.vertices = v
        points = [(float(a), float(b)) for a, b in v]
        # (a_north, a_east, b_north, b_east, ab_north, ab_east, |ab|^2) per edge a -> b
        self._edges = [
            (an, ae, bn, be, bn - an, be - ae, (bn - an) * (bn - an) + (be - ae) * (be - ae))
            for (an, ae), (bn, be) in zip(points, points[1:] + points[:1], strict=True)
        ]

    @classmethod
    def rectangle(cls, north: float, east: float) -> Geofence:
        """The search area [0, north] x [0, east] of a paper profile."""
        return cls(np.array([[0.0, 0.0], [north, 0.0], [north, east], [0.0, east]]))

    def contains(self, point: FloatArray | tuple[float, float]) -> bool:
        """Ray casting; points on an edge count as inside (the distance to the edges is only
        needed where the ray says outside, which is rare in flight)."""
        x, y = float(point[0]), float(point[1])
        inside = False
        for an, ae, bn, be, _, _, _ in self._edges:
            if (ae > y) != (be > y):
                cross = an + (y - ae) * (bn - an) / (be - ae)
                if x < cross:
                    inside = not inside
        return inside or self._nearest(x, y)[0] <= 1e-9

    def clamp(self, point: FloatArray) -> FloatArray:
        """``point`` if inside, else the nearest point on the fence's boundary."""
        p = np.asarray(point, dtype=float)
        if self.contains(p):
            return p
        _, n, e = self._nearest(float(p[0]), float(p[1]))
        return np.array([n, e])

    def clamp_xy(self, north: float, east: float) -> tuple[float, float]:
        """:meth:`clamp` of the point (north, east), on floats."""
        if self.contains((north, east)):
            return north, east
        _, n, e = self._nearest(north, east)
        return n, e

    def distance(self, north: float, east: float) -> float:
        """Distance to the boundary, metres (inside or out)."""
        return self._nearest(north, east)[0]

    def nearest(self, north: float, east: float) -> tuple[float, float]:
        """The nearest point on the boundary."""
        _, n, e = self._nearest(north, east)
        return n, e

    def inset(self, margin: float) -> Geofence:
        """The fence with every edge moved ``margin`` metres inwards (a convex polygon, as a
        site fence is; each vertex is where its two moved edges meet)."""
        if margin <= 0:
            return self
        v = self.vertices
        signed_area = 0.5 * float(
            np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1])
        )
        # (north, east) is a left-handed plane: a positive area here is a clockwise ring on a map
        turn = 1.0 if signed_area > 0 else -1.0
        moved = []
        for (an, ae), (bn, be) in zip(v, np.roll(v, -1, axis=0), strict=True):
            dn, de = bn - an, be - ae
            length = math.hypot(dn, de)
            # inward normal of edge a -> b
            nn, ne = -de / length * turn, dn / length * turn
            moved.append((an + nn * margin, ae + ne * margin, dn, de))
        out = []
        for i in range(len(moved)):
            pn, pe, pdn, pde = moved[i - 1]
            qn, qe, qdn, qde = moved[i]
            cross = pdn * qde - pde * qdn
            if abs(cross) < 1e-12:
                out.append((qn, qe))
                continue
            t = ((qn - pn) * qde - (qe - pe) * qdn) / cross
            out.append((pn + t * pdn, pe + t * pde))
        inner = Geofence(np.array(out))
        if not all(self.contains(p) and self.distance(*p) >= margin - 1e-6 for p in out):
            raise ValueError(f"the geofence is too small (or not convex) for a {margin:g} m inset")
        return inner

    def _nearest(self, x: float, y: float) -> tuple[float, float, float]:
        """Distance to the boundary and the nearest boundary point (first edge on ties)."""
        best, bn_, be_ = math.inf, math.nan, math.nan
        for an, ae, _, _, dn, de, length2 in self._edges:
            t = ((x - an) * dn + (y - ae) * de) / length2 if length2 > 0 else 0.0
            t = 0.0 if t < 0.0 else 1.0 if t > 1.0 else t
            n, e = an + t * dn, ae + t * de
            d = math.sqrt((n - x) * (n - x) + (e - y) * (e - y))
            if d < best:
                best, bn_, be_ = d, n, e
        return best, bn_, be_
