"""The geofence a profile asks for: its field polygon, else the search area's rectangle; and what
a geo-referenced (site) profile adds: the fence watch, the guidance fence. :func:`site_geometry`
builds them all at once, from one frame and one fence, for a flight."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from companion.geofence import Geofence
from companion.link.local_frame import LocalFrame
from companion.mission.fence_watch import FenceWatch
from mdm_profiles import MissionProfile


@dataclass(frozen=True)
class SiteGeometry:
    """A profile's frame and fences, each built once."""

    frame: LocalFrame
    """The profile's own frame: NED metres around its origin."""
    fence: Geofence
    """The fence as the profile draws it (local north, east)."""
    guidance: Geofence
    """What commanded points stay inside: ``fence`` moved ``site.fence_inset`` inwards (room
    to brake), else the area's rectangle."""
    watch: FenceWatch | None
    """The fence and search area checked on the GPS position (site profiles only)."""


def site_geometry(profile: MissionProfile) -> SiteGeometry:
    """``profile``'s frame, fence, guidance fence and fence watch."""
    frame = profile_frame(profile)
    fence = _fence(profile, frame)
    site = profile.site
    if site is None:
        return SiteGeometry(frame, fence, fence, None)
    area = Geofence.rectangle(profile.area.north, profile.area.east)
    watch = FenceWatch(fence, area, site.start_margin)
    return SiteGeometry(frame, fence, fence.inset(site.fence_inset), watch)


def fence_for(profile: MissionProfile) -> Geofence:
    """Local (north, east) geofence; WGS84 vertices are converted by the link layer's frame."""
    return _fence(profile, profile_frame(profile))


OWN_FRAME_MARGIN = 1000.0
"""Metres beyond the area's diagonal within which a profile without ``site`` is flown in the
profile's frame (docs/companion.md, *Frames*)."""


def own_frame_reach(profile: MissionProfile) -> float:
    """How far from the profile's origin a vehicle's local origin may lie for a profile
    without ``site`` to be flown in the profile's frame (the emulator's vehicles boot at their
    start points in the area); a vehicle farther away (a SITL booted at its default home) is
    flown in its own frame, the area starting at its origin."""
    return math.hypot(profile.area.north, profile.area.east) + OWN_FRAME_MARGIN


def profile_frame(profile: MissionProfile) -> LocalFrame:
    """The profile's own frame: NED metres around its origin."""
    return LocalFrame(profile.origin.lat, profile.origin.lon, profile.origin.alt)


def guidance_fence(profile: MissionProfile) -> Geofence:
    """:attr:`SiteGeometry.guidance` of ``profile``."""
    return site_geometry(profile).guidance


def fence_watch(profile: MissionProfile) -> FenceWatch | None:
    """:attr:`SiteGeometry.watch` of ``profile``."""
    return site_geometry(profile).watch


def _fence(profile: MissionProfile, frame: LocalFrame) -> Geofence:
    site = profile.site
    if site is None:
        return Geofence.rectangle(profile.area.north, profile.area.east)
    local = [frame.to_local(p.lat, p.lon, profile.origin.alt)[:2] for p in site.geofence]
    return Geofence(np.array(local))
