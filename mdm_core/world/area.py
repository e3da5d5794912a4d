"""The rectangular search region and what happens to points that leave it."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

BoundaryRule = Literal["reflect", "clip"]


@dataclass(frozen=True)
class Area:
    """Axis-aligned rectangle [0, north] x [0, east] in metres from the profile's origin."""

    north: float
    """Extent along north (the paper's L), metres."""
    east: float
    """Extent along east (the paper's W), metres."""

    def __post_init__(self) -> None:
        if not (self.north > 0 and self.east > 0):
            raise ValueError(f"Area extents must be > 0 m, got {self.north} x {self.east}")

    @property
    def size(self) -> FloatArray:
        return np.array([self.north, self.east])

    def contains(self, points: FloatArray, margin: float = 0.0) -> NDArray[np.bool_]:
        """True where points (..., 2) lie inside the area grown by ``margin`` metres."""
        lo = -margin
        hi = self.size + margin
        return np.asarray(np.all((points >= lo) & (points <= hi), axis=-1))

    def fold(self, points: FloatArray, rule: BoundaryRule) -> FloatArray:
        """Bring points (..., 2) back inside: mirror them at the walls, or clip them to the walls."""
        size = self.size
        if rule == "clip":
            return np.clip(points, 0.0, size)
        period = 2.0 * size
        # points mod period (as np.mod, twice as fast; exact for points already in [0, period)),
        # then mirrored past the far wall: period - f is below f exactly where f > size, so
        # the smaller of the two is the mirrored point. Two buffers (the walks fold large arrays).
        folded = np.divide(points, period)
        np.floor(folded, out=folded)
        folded *= period
        np.subtract(points, folded, out=folded)
        mirrored = np.subtract(period, folded)
        return np.minimum(folded, mirrored, out=folded)

    def perimeter_point(self, s: FloatArray) -> FloatArray:
        """Points at arc length fraction s in [0, 1) along the boundary, counter-clockwise from 0."""
        n, e = self.north, self.east
        d = np.mod(np.asarray(s, dtype=float), 1.0) * 2.0 * (n + e)
        out = np.empty((*d.shape, 2))
        # Walk the four sides: east along north=0, north along east=E, back, and down.
        side1 = d < e
        side2 = (d >= e) & (d < e + n)
        side3 = (d >= e + n) & (d < 2 * e + n)
        side4 = d >= 2 * e + n
        out[side1] = np.stack([np.zeros(side1.sum()), d[side1]], axis=-1)
        out[side2] = np.stack([d[side2] - e, np.full(side2.sum(), e)], axis=-1)
        out[side3] = np.stack([np.full(side3.sum(), n), e - (d[side3] - e - n)], axis=-1)
        out[side4] = np.stack([n - (d[side4] - 2 * e - n), np.zeros(side4.sum())], axis=-1)
        return out
