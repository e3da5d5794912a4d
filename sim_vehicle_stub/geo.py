"""Conversion between the profile's local frame (north, east, up from the origin) and WGS84."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pymap3d
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class GeoFrame:
    """The profile origin; only the MAVLink edge converts with it."""

    lat: float
    lon: float
    alt: float
    """AMSL altitude of the origin (and of every home), m."""

    def to_geodetic(
        self, north: FloatArray, east: FloatArray, up: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(lat deg, lon deg, alt AMSL m) of local points."""
        lat, lon, alt = pymap3d.ned2geodetic(
            north, east, -np.asarray(up), self.lat, self.lon, self.alt
        )
        return np.asarray(lat), np.asarray(lon), np.asarray(alt)

    def to_local(self, lat: float, lon: float, alt: float) -> tuple[float, float, float]:
        """(north, east, up) metres of a WGS84 point with AMSL altitude."""
        n, e, d = pymap3d.geodetic2ned(lat, lon, alt, self.lat, self.lon, self.alt)
        return float(n), float(e), -float(d)
