"""A polygon geofence in the local (north, east) frame: containment and the nearest inside point."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


class Geofence:
    """A simple polygon (vertices in order, metres north/east of the profile origin)."""

    def __init__(self, vertices: FloatArray) -> None:
        v = np.asarray(vertices, dtype=float)
        if v.ndim != 2 or v.shape[1] != 2 or len(v) < 3:
            raise ValueError(f"a geofence needs >= 3 (north, east) vertices, got shape {v.shape}")
        self.vertices = v

    @classmethod
    def rectangle(cls, north: float, east: float) -> Geofence:
        """The search area [0, north] x [0, east] of a paper profile."""
        return cls(np.array([[0.0, 0.0], [north, 0.0], [north, east], [0.0, east]]))

    def contains(self, point: FloatArray) -> bool:
        """Ray casting; points on an edge count as inside."""
        if self._edge_distance(point)[0] <= 1e-9:
            return True
        x, y = float(point[0]), float(point[1])
        inside = False
        v = self.vertices
        for a, b in zip(v, np.roll(v, -1, axis=0), strict=True):
            if (a[1] > y) != (b[1] > y):
                cross = a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
                if x < cross:
                    inside = not inside
        return inside

    def clamp(self, point: FloatArray) -> FloatArray:
        """``point`` if inside, else the nearest point on the fence's boundary."""
        p = np.asarray(point, dtype=float)
        if self.contains(p):
            return p
        return self._edge_distance(p)[1]

    def _edge_distance(self, point: FloatArray) -> tuple[float, FloatArray]:
        a = self.vertices
        b = np.roll(a, -1, axis=0)
        ab = b - a
        t = np.clip(np.einsum("kd,kd->k", point - a, ab) / np.einsum("kd,kd->k", ab, ab), 0, 1)
        nearest = a + t[:, None] * ab
        d = np.linalg.norm(nearest - point, axis=1)
        i = int(np.argmin(d))
        return float(d[i]), np.asarray(nearest[i])
