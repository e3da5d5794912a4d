"""Conversion between the profile's local frame (north, east, up from the origin) and WGS84.

Uses PX4's own map projection (azimuthal equidistant on a sphere of radius 6371 km, altitude
separate: ``alt = origin alt + up``), so GLOBAL_POSITION_INT and LOCAL_POSITION_NED agree the way
they do on a real PX4 over a 20 km area, and the conversion is cheap enough to run for every
vehicle at every telemetry tick.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
EARTH_RADIUS = 6371000.0


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
        lat0, lon0 = math.radians(self.lat), math.radians(self.lon)
        x = np.asarray(north, dtype=float) / EARTH_RADIUS
        y = np.asarray(east, dtype=float) / EARTH_RADIUS
        c = np.hypot(x, y)
        sin_c, cos_c = np.sin(c), np.cos(c)
        safe = np.where(c > 0, c, 1.0)
        lat = np.arcsin(cos_c * math.sin(lat0) + x * sin_c * math.cos(lat0) / safe)
        lon = lon0 + np.arctan2(y * sin_c, c * math.cos(lat0) * cos_c - x * math.sin(lat0) * sin_c)
        lat = np.where(c > 0, lat, lat0)
        lon = np.where(c > 0, lon, lon0)
        return np.degrees(lat), np.degrees(lon), self.alt + np.asarray(up, dtype=float)

    def to_local(self, lat: float, lon: float, alt: float) -> tuple[float, float, float]:
        """(north, east, up) metres of a WGS84 point with AMSL altitude."""
        lat0, lon0 = math.radians(self.lat), math.radians(self.lon)
        la, lo = math.radians(lat), math.radians(lon)
        cos_dlon = math.cos(lo - lon0)
        arg = math.sin(lat0) * math.sin(la) + math.cos(lat0) * math.cos(la) * cos_dlon
        c = math.acos(max(-1.0, min(1.0, arg)))
        k = 1.0 if abs(c) < 1e-12 else c / math.sin(c)
        north = k * (math.cos(lat0) * math.sin(la) - math.sin(lat0) * math.cos(la) * cos_dlon)
        east = k * math.cos(la) * math.sin(lo - lon0)
        return north * EARTH_RADIUS, east * EARTH_RADIUS, float(alt) - self.alt
