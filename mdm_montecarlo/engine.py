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
the policy (``compiled_step.CompiledPolicy``: the numpy ``SearchPolicy``'s step and waypoint
draws, bit for bit, from the same random stream); the companion flies the numpy policy.

Randomness: runs are cut into blocks of ``block_runs``; block b draws from
SeedSequence([seed, b]) alone, so results are identical for any number of workers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mdm_core.search import Observation
from mdm_core.search.from_profile import policy_config
from mdm_core.world import Scenario
from mdm_montecarlo.compiled_step import CompiledPolicy
from mdm_montecarlo.compiled_tracks import compiled_tracks
from mdm_montecarlo.remembered import RememberedTargets
from mdm_montecarlo.round_kernels import advance, legs, record
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
    tracks = compiled_tracks(scenario, n_runs, rng_targets, cap)
    start = scenario.start_positions(n_runs, n_vehicles, profile.fleet.start, rng_start)

    n = n_runs * n_vehicles
    run_of = np.repeat(np.arange(n_runs), n_vehicles)
    position = start.reshape(n, 2).copy()
    time = np.zeros(n)
    state = policy.start(position, time, rng_policy)

    targets = scenario.targets
    m = targets.count
    real = ~targets.false_mask
    first = np.full((n, m), np.inf)
    stop = np.full(n_runs, cap)
    active = np.ones(n, dtype=bool)
    events = 0
    appear = targets.appear_times
    remembered = RememberedTargets(policy.config.memory_radius, tracks, n, m)
    lifetimes, radii, memory_rule = policy.lifetimes, policy.radii, policy.memory_rule

    while True:
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        runs = run_of[idx]
        t = time[idx]
        unit, leg, left, horizon, until = legs(
            state.waypoint,
            position,
            time,
            state.level,
            state.entered,
            state.blind_until,
            lifetimes,
            stop,
            idx,
            runs,
            speed,
        )
        eligible = remembered.eligible(state, idx, runs, t, policy.checks_exactly(state, idx))
        seg_start, seg_velocity = tracks.segments(until)
        # position and time move to the event; the same ignore rules as the policy's step,
        # so no contact is reported that it would drop.
        reached, contacts, target_pos = advance(
            state.level,
            state.blind_until,
            state.memory,
            state.memory_count,
            position,
            time,
            state.waypoint,
            idx,
            runs,
            unit,
            leg,
            left,
            horizon,
            eligible,
            radii,
            memory_rule,
            targets.false_mask,
            appear,
            seg_start,
            seg_velocity,
            tracks.grid_dt,
            tracks.max_speed,
            tracks.moving,
            speed,
        )
        new_t = time[idx]
        new_x = position[idx]

        obs = Observation(
            time=new_t,
            position=new_x,
            reached=reached,
            contacts=contacts,
            contact_positions=target_pos,
        )
        outcome = policy.step(state, idx, obs, rng_policy)
        remembered.forget(idx[outcome.confirmed])
        events += 1

        record(
            first,
            stop,
            active,
            outcome.confirmed,
            outcome.new_confirmations,
            idx,
            runs,
            time,
            real,
            n_vehicles,
            duration,
            cap,
        )

    per_vehicle = first.reshape(n_runs, n_vehicles, m)
    return BlockResult(block, per_vehicle, events, float(time.sum()))
