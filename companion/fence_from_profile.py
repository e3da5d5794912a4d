"""The geofence a profile asks for: its field polygon, else the search area's rectangle; and what
a geo-referenced (site) profile adds: the fence watch, the guidance fence, the start point."""

from __future__ import annotations

import numpy as np

from companion.geofence import Geofence
from companion.link.local_frame import LocalFrame
from companion.mission.fence_watch import FenceWatch
from mdm_profiles import MissionProfile


def fence_for(profile: MissionProfile) -> Geofence:
    """Local (north, east) geofence; WGS84 vertices are converted by the link layer's frame."""
    site = profile.site
    if site is None:
        return Geofence.rectangle(profile.area.north, profile.area.east)
    frame = profile_frame(profile)
    local = [frame.to_local(p.lat, p.lon, profile.origin.alt)[:2] for p in site.geofence]
    return Geofence(np.array(local))


def profile_frame(profile: MissionProfile) -> LocalFrame:
    """The profile's own frame: NED metres around its origin."""
    return LocalFrame(profile.origin.lat, profile.origin.lon, profile.origin.alt)


def guidance_fence(profile: MissionProfile) -> Geofence:
    """What commanded points stay inside: the site fence moved ``site.fence_inset`` inwards
    (room to brake), else the area's rectangle."""
    fence = fence_for(profile)
    return fence if profile.site is None else fence.inset(profile.site.fence_inset)


def fence_watch(profile: MissionProfile) -> FenceWatch | None:
    """The fence and search area checked on the GPS position (site profiles only)."""
    if profile.site is None:
        return None
    area = Geofence.rectangle(profile.area.north, profile.area.east)
    return FenceWatch(fence_for(profile), area, profile.site.start_margin)
