"""The partitioned lawnmower baselines (policy.kind lm1, lm2) in the Monte-Carlo engine.

Each run draws its targets and start points from the block's streams as every engine does
(SeedSequence([seed, block])), plans its team (mdm_core.search.lawnmower.plan: cells, who
sweeps which, the lanes) and flies every lane compiled (mdm_montecarlo.kernels.lawnmower_kernel).
The plan has no randomness, so results are the same for any number of workers.
"""

from __future__ import annotations

import numpy as np

from mdm_core.search import lawnmower
from mdm_core.world import Scenario
from mdm_montecarlo.engines.engine import BlockResult, block_rngs, departures
from mdm_montecarlo.kernels.compiled_tracks import shared_tracks
from mdm_montecarlo.kernels.lawnmower_kernel import fly_lawnmower
from mdm_profiles import MissionProfile

LAWNMOWER_KINDS = ("lm1", "lm2")


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


def run_lawnmower_block(profile: MissionProfile, seed: int, block: int, n_runs: int) -> BlockResult:
    """Simulate ``n_runs`` missions of an lm1/lm2 profile (block ``block`` of ``seed``);
    ``events`` counts the legs flown."""
    scenario = Scenario.from_profile(profile)
    rng_targets, rng_start, _ = block_rngs(seed, block)
    n_vehicles = profile.fleet.vehicles
    cap = max(profile.mission.ts_cap, profile.mission.duration)
    tracks = shared_tracks(scenario, n_runs, rng_targets, cap)
    start = scenario.start_positions(n_runs, n_vehicles, profile.fleet.start, rng_start)
    plans = [team_plan(profile, start[r]) for r in range(n_runs)]
    waypoints = np.concatenate([p.waypoints for p in plans])
    seg_start, seg_velocity = tracks.segments(cap)
    targets = scenario.targets
    n = n_runs * n_vehicles
    first = np.full((n, targets.count), np.inf)
    legs, simulated = fly_lawnmower(
        profile.policy.kind == "lm2",
        waypoints,
        start.reshape(n, 2).copy(),
        n_vehicles,
        profile.fleet.speed,
        profile.mission.duration,
        cap,
        np.asarray(scenario.area.size, dtype=float),
        search_spiral(profile),
        search_hold(profile),
        scenario.sensors[0].radius,
        scenario.confirmation.radius,
        targets.appear_times,
        ~targets.false_mask,
        seg_start,
        seg_velocity,
        tracks.grid_dt,
        tracks.moving,
        tracks.max_speed,
        first,
    )
    gone = departures(profile, tracks, cap)
    return BlockResult(block, first.reshape(n_runs, n_vehicles, -1), legs, simulated, gone=gone)
