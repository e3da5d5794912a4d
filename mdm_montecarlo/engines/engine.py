"""Event-driven batched missions: every (run, vehicle) lane flies straight legs between events.

Between two events a vehicle flies a straight line at constant speed (the tau-lag transient of
a 0.33 s loop shifts a 4 km leg by under 7 m; ``reference.py`` checks the result against dt-stepping
of the full dynamics). An event is the earliest of: the waypoint is reached, the active sensor's
disc around an eligible target is entered (solved in closed form by
``mdm_core.world.first_entry_time``, piece by piece between the nodes of a dynamic
target's path grid), the level's decaying index runs out, the run's stop time. The policy
(mdm_core.search) is stepped at every event with the sensor contacts the world reports, so a
lane is exactly what a live vehicle would do, only with time jumping from event to event. Which
targets a vehicle remembers confirming (its memory) is checked at the start of each leg.

Vehicles do not communicate, so lanes of one run only share the targets; the team's result is
the minimum over its vehicles of each target's first confirmation time.

Speed: a round's loops over the lanes are compiled with numba (``round_kernels``), and so is
the policy (``compiled_step``: the numpy ``SearchPolicy``'s step and waypoint draws, bit for
bit, from the same random stream); ``block_rounds.fly_rounds`` runs the rounds one after
another in one compiled loop, back in Python only to grow the dynamic targets' paths. The
companion flies the numpy policy.

Randomness: runs are cut into blocks of ``block_runs``; block b draws from
SeedSequence([seed, b]) alone, so results are identical for any number of workers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mdm_core.search.from_profile import policy_config
from mdm_core.world import Scenario, TargetTracks
from mdm_montecarlo.kernels.block_rounds import DONE, fly_rounds
from mdm_montecarlo.kernels.compiled_step import CompiledPolicy
from mdm_montecarlo.kernels.compiled_tracks import shared_tracks
from mdm_montecarlo.kernels.compiled_waypoints import RULES
from mdm_montecarlo.kernels.remembered import RememberedTargets
from mdm_profiles import MissionProfile

FloatArray = NDArray[np.float64]
BLOCK_RUNS = 1000


@dataclass(frozen=True)
class BlockResult:
    """First confirmation time of every target by every vehicle, for one block of runs."""

    first_block: int
    per_vehicle: FloatArray
    """(runs, vehicles, targets) seconds; inf where that vehicle never confirmed the target."""
    events: int
    """Policy steps taken (a measure of work)."""
    sim_seconds: float
    """Vehicle-seconds simulated (sum over lanes)."""
    followed: int | None = None
    """Swarm baselines: particle-iterations that followed a best heard from a peer (``events``
    counts all particle-iterations); None for the methods without communication."""
    gone: FloatArray | None = None
    """(runs, targets) when each target left the area (inf: never), with
    ``mission.ts_rule: confirmed_or_gone`` and moving targets; else None."""


def departures(profile: MissionProfile, tracks: TargetTracks, until: float) -> FloatArray | None:
    """The targets' departure times when the profile's T_S counts them (else None)."""
    if profile.mission.ts_rule != "confirmed_or_gone" or not tracks.moving:
        return None
    return tracks.departures(until)


def block_rngs(seed: int, block: int) -> tuple[np.random.Generator, ...]:
    """Independent generators for the targets, the start positions and the policy of a block."""
    children = np.random.SeedSequence([seed, block]).spawn(3)
    return tuple(np.random.default_rng(c) for c in children)


def run_block(profile: MissionProfile, seed: int, block: int, n_runs: int) -> BlockResult:
    """Simulate ``n_runs`` missions of the profile; block index ``block`` fixes the random streams."""
    scenario = Scenario.from_profile(profile)
    policy = CompiledPolicy(policy_config(profile))
    rng_targets, rng_start, rng_policy = block_rngs(seed, block)
    n_vehicles = profile.fleet.vehicles
    speed = profile.fleet.speed
    duration = profile.mission.duration
    cap = max(profile.mission.ts_cap, duration)
    tracks = shared_tracks(scenario, n_runs, rng_targets, cap)
    start = scenario.start_positions(n_runs, n_vehicles, profile.fleet.start, rng_start)

    n = n_runs * n_vehicles
    position = start.reshape(n, 2).copy()
    time = np.zeros(n)
    state = policy.start(position, time, rng_policy)
    assert policy.table is not None  # else start raised the numpy draws' error

    targets = scenario.targets
    m = targets.count
    first = np.full((n, m), np.inf)
    stop = np.full(n_runs, cap)
    gone = departures(profile, tracks, cap)
    gone_or_inf = np.full((n_runs, m), np.inf) if gone is None else gone
    if gone is not None:  # a run whose targets all leave unconfirmed ends when the last does
        last = np.where(~targets.false_mask, gone, -np.inf).max(axis=1)
        stop = np.minimum(np.maximum(last, duration), cap)
    active = np.ones(n, dtype=bool)
    remembered = RememberedTargets(policy.config.memory_radius, tracks, n, m)
    config = policy.config
    events = 0
    visible = tracks.max_speed  # the first round checks its windows before any path is drawn
    seg_start, seg_velocity = tracks.segments(0.0)
    while True:
        status, reach, rounds, state.memory = fly_rounds(
            state.level,
            state.entered,
            state.blind_until,
            state.anchor,
            state.waypoint,
            state.memory,
            state.memory_count,
            position,
            time,
            active,
            first,
            stop,
            gone_or_inf,
            remembered.known,
            remembered.until,
            remembered.speed,
            visible,
            tracks.max_speed,
            seg_start,
            seg_velocity,
            tracks.filled,
            tracks.grid_dt,
            tracks.moving,
            targets.false_mask,
            targets.appear_times,
            ~targets.false_mask,
            policy.lifetimes,
            policy.radii,
            policy.memory_rule,
            float(config.memory_radius),
            float(config.fallback_blind_time),
            policy.table,
            policy.area,
            RULES[config.out_of_area],
            config.waypoint_origin == "anchor",
            config.confine_to_detection,
            n_vehicles,
            speed,
            duration,
            cap,
            rng_policy,
        )
        events += rounds
        if status == DONE:
            break
        if events:  # the interrupted round checks against the paths drawn before it
            visible = tracks.max_speed
        seg_start, seg_velocity = tracks.segments(reach)

    per_vehicle = first.reshape(n_runs, n_vehicles, m)
    return BlockResult(block, per_vehicle, events, float(time.sum()), gone=gone)
