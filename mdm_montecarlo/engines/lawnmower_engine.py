"""The partitioned lawnmower baselines (policy.kind lm1, lm2) in the Monte-Carlo engine.

Each run draws its targets and start points from the block's streams as every engine does
(SeedSequence([seed, block])), plans its team (mdm_core.search.lawnmower.plan: cells, who
sweeps which, the lanes) and flies every lane compiled (mdm_montecarlo.kernels.lawnmower_kernel).
The plan has no randomness, so results are the same for any number of workers.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mdm_core.search.lawnmower_profile import search_hold, search_spiral, team_plan
from mdm_core.world import Scenario, TargetTracks
from mdm_montecarlo.engines.configuration import Configuration
from mdm_montecarlo.engines.engine import BlockResult, block_rngs, departures
from mdm_montecarlo.kernels.compiled_tracks import shared_tracks
from mdm_montecarlo.kernels.lawnmower_kernel import fly_lawnmower
from mdm_profiles import MissionProfile

FloatArray = NDArray[np.float64]


def run_lawnmower_block(
    configuration: Configuration, seed: int, block: int, n_runs: int
) -> BlockResult:
    """Simulate ``n_runs`` missions of an lm1/lm2 configuration (block ``block`` of ``seed``);
    ``events`` counts the legs flown."""
    profile, scenario = configuration.profile, configuration.scenario
    rng_targets, rng_start, _ = block_rngs(seed, block)
    n_vehicles = profile.fleet.vehicles
    cap = max(profile.mission.ts_cap, profile.mission.duration)
    tracks = shared_tracks(scenario, n_runs, rng_targets, cap)
    start = scenario.start_positions(n_runs, n_vehicles, profile.fleet.start, rng_start)
    first, legs, simulated = fly_planned(profile, scenario, tracks, start, cap)
    gone = departures(profile, tracks, cap)
    return BlockResult(block, first.reshape(n_runs, n_vehicles, -1), legs, simulated, gone=gone)


def fly_planned(
    profile: MissionProfile, scenario: Scenario, tracks: TargetTracks, start: FloatArray, cap: float
) -> tuple[FloatArray, int, float]:
    """Every run's team plan flown compiled: ``start`` (runs, vehicles, 2) -> the first
    confirmations (runs x vehicles, targets), the legs flown and the time simulated."""
    n_runs, n_vehicles = start.shape[:2]
    waypoints = np.concatenate([team_plan(profile, start[r]).waypoints for r in range(n_runs)])
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
    return first, legs, simulated
