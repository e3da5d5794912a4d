"""Conversion between the profile's local frame (north, east, up from the origin) and WGS84.

The same convention as the companion (pymap3d's ``ned2geodetic`` / ``geodetic2ned`` on the
WGS84 ellipsoid, the local frame being the origin's tangent plane), so positions agree to the
millimetre across the project. The forward direction runs for every vehicle at every telemetry
tick, so it is written out (closed-form ECEF to geodetic, Heikkinen 1982: compiled arithmetic
between numpy's transcendental functions, sim_vehicle_stub/wgs84_kernels.py) instead of calling
pymap3d, which costs about a millisecond per call.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import pymap3d
from numpy.typing import NDArray

from sim_vehicle_stub.wgs84_kernels import (
    E2,
    A,
    arctan_argument_and_height,
    cbrt_argument,
    heikkinen_g,
    to_ecef,
)

FloatArray = NDArray[np.float64]


def _geodetic2ecef(lat: float, lon: float, h: float) -> tuple[float, float, float]:
    n = A / math.sqrt(1 - E2 * math.sin(lat) ** 2)
    return (
        (n + h) * math.cos(lat) * math.cos(lon),
        (n + h) * math.cos(lat) * math.sin(lon),
        (n * (1 - E2) + h) * math.sin(lat),
    )


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
        n, e, u = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (north, east, up)))
        shape = n.shape
        x, y, z = to_ecef(n.ravel(), e.ravel(), u.ravel(), (x0, y0, z0), sl, cl, so, co)
        p = np.hypot(x, y)
        g = heikkinen_g(z, p)
        s = np.cbrt(cbrt_argument(z, p, g**3))
        tangent, h = arctan_argument_and_height(z, p, g, s)
        lat, lon = np.arctan(tangent).reshape(shape), np.arctan2(y, x).reshape(shape)
        return np.degrees(lat), np.degrees(lon), h.reshape(shape)[()]

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
