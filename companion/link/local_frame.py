"""WGS84 <-> the profile's local NED frame (pymap3d). The only place that knows about WGS84."""

from __future__ import annotations

from dataclasses import dataclass

import pymap3d


@dataclass(frozen=True)
class LocalFrame:
    """NED metres around a geodetic origin (the profile's origin: lat, lon in degrees, alt AMSL m)."""

    lat: float
    lon: float
    alt: float

    def to_geodetic(self, north: float, east: float, down: float) -> tuple[float, float, float]:
        """(lat, lon, alt AMSL) of a local point."""
        lat, lon, alt = pymap3d.ned2geodetic(north, east, down, self.lat, self.lon, self.alt)
        return float(lat), float(lon), float(alt)

    def to_local(self, lat: float, lon: float, alt: float) -> tuple[float, float, float]:
        """(north, east, down) of a geodetic point."""
        n, e, d = pymap3d.geodetic2ned(lat, lon, alt, self.lat, self.lon, self.alt)
        return float(n), float(e), float(d)
