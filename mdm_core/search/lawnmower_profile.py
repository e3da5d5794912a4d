"""A profile's lawnmower team (policy.kind lm1, lm2): its plan, the lm2 confirmation search and
the hold after a search in vain, as the Monte-Carlo engine and the companion both fly them (one
source: mdm_montecarlo.engines.lawnmower_engine and companion.mission.lawnmower_core)."""

from __future__ import annotations

import numpy as np

from mdm_core.search import lawnmower
from mdm_profiles import MissionProfile


def sweep_radius(profile: MissionProfile) -> float:
    """The radius the lanes are spaced for: the confirmation sensor's (lm1) or the first
    detection sensor's (lm2)."""
    sensors = profile.sensors
    return sensors[0].radius if profile.policy.kind == "lm2" else sensors[-1].radius


def team_plan(profile: MissionProfile, starts: np.ndarray) -> lawnmower.Plan:
    """The lawnmower plan of the profile's team from ``starts`` (vehicles, 2)."""
    spec = profile.policy.lawnmower
    spacing = lawnmower.lane_spacing(sweep_radius(profile), spec.overlap)
    return lawnmower.plan((profile.area.north, profile.area.east), starts, spacing)


def search_spiral(profile: MissionProfile) -> np.ndarray:
    """lm2's confirmation search (offsets from the point of detection)."""
    spec = profile.policy.lawnmower
    confirm = profile.sensors[-1].radius
    return lawnmower.spiral(
        profile.sensors[0].radius, 2.0 * confirm, spec.chords_per_turn, spec.search == "spiral_in"
    )


def search_hold(profile: MissionProfile) -> float:
    """Seconds a target searched for in vain is ignored: policy.lawnmower.search_hold, or -1
    (None): until the vehicle's pass over its cell ends."""
    hold = profile.policy.lawnmower.search_hold
    return -1.0 if hold is None else hold
