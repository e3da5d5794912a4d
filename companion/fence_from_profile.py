"""The geofence a profile asks for: its field polygon, else the search area's rectangle."""

from __future__ import annotations

import numpy as np

from companion.geofence import Geofence
from companion.link.geo import LocalFrame
from mdm_profiles import MissionProfile


def fence_for(profile: MissionProfile) -> Geofence:
    """Local (north, east) geofence; WGS84 vertices are converted by the link layer's frame."""
    site = profile.site
    if site is None:
        return Geofence.rectangle(profile.area.north, profile.area.east)
    frame = LocalFrame(profile.origin.lat, profile.origin.lon, profile.origin.alt)
    local = [frame.to_local(p.lat, p.lon, profile.origin.alt)[:2] for p in site.geofence]
    return Geofence(np.array(local))
