"""Conversion between the profile's local frame (north, east, up from the origin) and WGS84.

The same convention as the companion (pymap3d's ``ned2geodetic`` / ``geodetic2ned`` on the
WGS84 ellipsoid, the local frame being the origin's tangent plane), so positions agree to the
millimetre across the project. The forward direction runs for every vehicle at every telemetry
tick, so it is written out in numpy (closed-form ECEF to geodetic, Heikkinen 1982) instead of
calling pymap3d, which costs about a millisecond per call.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import pymap3d
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

_A = 6378137.0
_F = 1 / 298.257223563
_B = _A * (1 - _F)
_E2 = _F * (2 - _F)
_EP2 = (_A**2 - _B**2) / _B**2


def _geodetic2ecef(lat: float, lon: float, h: float) -> tuple[float, float, float]:
    n = _A / math.sqrt(1 - _E2 * math.sin(lat) ** 2)
    return (
        (n + h) * math.cos(lat) * math.cos(lon),
        (n + h) * math.cos(lat) * math.sin(lon),
        (n * (1 - _E2) + h) * math.sin(lat),
    )


def _ecef2geodetic(
    x: FloatArray, y: FloatArray, z: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Latitude, longitude (rad) and height of ECEF points, closed form (Heikkinen 1982); each
    square is computed once (the same operations give the same bits)."""
    p = np.hypot(x, y)
    z2, p2 = z**2, p**2
    f = 54 * _B**2 * z2
    g = p2 + (1 - _E2) * z2 - _E2 * (_A**2 - _B**2)
    c = _E2**2 * f * p2 / g**3
    s = np.cbrt(1 + c + np.sqrt(c**2 + 2 * c))
    pp = f / (3 * (s + 1 / s + 1) ** 2 * g**2)
    q = np.sqrt(1 + 2 * _E2**2 * pp)
    r0 = -(pp * _E2 * p) / (1 + q) + np.sqrt(
        _A**2 / 2 * (1 + 1 / q) - pp * (1 - _E2) * z2 / (q * (1 + q)) - pp * p2 / 2
    )
    d2 = (p - _E2 * r0) ** 2
    u = np.sqrt(d2 + z2)
    v = np.sqrt(d2 + (1 - _E2) * z2)
    z0 = _B**2 * z / (_A * v)
    h = u * (1 - _B**2 / (_A * v))
    return np.arctan((z + _EP2 * z0) / p), np.arctan2(y, x), h


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
        """(lat deg, lon deg, alt m) of local points, as ``pymap3d.ned2geodetic``."""
        x0, y0, z0, sl, cl, so, co = self._tangent
        n, e, u = (np.asarray(a, dtype=float) for a in (north, east, up))
        x = x0 - so * e - sl * co * n + cl * co * u
        y = y0 + co * e - sl * so * n + cl * so * u
        z = z0 + cl * n + sl * u
        lat, lon, h = _ecef2geodetic(x, y, z)
        return np.degrees(lat), np.degrees(lon), h

    @functools.cached_property
    def _tangent(self) -> tuple[float, ...]:
        """The origin in ECEF and the sines and cosines of its latitude and longitude."""
        lat0, lon0 = math.radians(self.lat), math.radians(self.lon)
        sl, cl = math.sin(lat0), math.cos(lat0)
        so, co = math.sin(lon0), math.cos(lon0)
        return (*_geodetic2ecef(lat0, lon0, self.alt), sl, cl, so, co)

    def to_local(self, lat: float, lon: float, alt: float) -> tuple[float, float, float]:
        """(north, east, up) metres of a WGS84 point, as ``pymap3d.geodetic2ned``."""
        n, e, d = pymap3d.geodetic2ned(lat, lon, alt, self.lat, self.lon, self.alt)
        return float(n), float(e), -float(d)
