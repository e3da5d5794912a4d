"""A dt-stepping reference of the engine's missions: full dynamics, sensors read every step.

It exists to check the shortcuts of ``engine.py`` (straight legs at constant speed, sensor-disc
entries solved in closed form, time jumping from event to event). Every lane is advanced by a
fixed step ``dt``:

1. guidance: ``pursuit_reference`` towards the policy's current waypoint at ``fleet.speed``;
2. dynamics: ``lag_step`` (exact tau-lag discretisation, reference held over the step) with
   ``fleet.tau``;
3. the waypoint counts as reached within ``fleet.acceptance_radius``;
4. sensors: ``mdm_core.world.contacts`` with the active sensor of each lane
   (``policy.sensor_radius``, ``policy.uses_confirmation_sensor``) against the targets that
   have appeared (``appear_times <= t``), at the targets' positions at t; with
   ``policy.redetection``, the detection sensor's contacts as well;
5. the same ``SearchPolicy`` is stepped for every lane, every step.

Nothing of the policy, world or dynamics is reimplemented here; only the clock differs from the
engine. The random streams are the engine's (``block_rngs``): a block of the reference has the
same targets, start positions and first waypoints as the engine's block; after the first event
the policy draws come in another order, so runs agree in distribution, not one by one.

Vehicles start at cruise: the initial velocity is the pursuit reference towards the first
waypoint (the engine flies every leg at ``fleet.speed`` from its start). The reference runs to
``mission.duration`` (or ``horizon``) only: it serves T_nc, not T_S.
"""

from __future__ import annotations

import math

import numpy as np

from mdm_core.dynamics import LagModel, lag_step, pursuit_reference
from mdm_core.search import Observation, SearchPolicy
from mdm_core.search.from_profile import policy_config
from mdm_core.world import Scenario, contacts
from mdm_montecarlo.engines.engine import BlockResult, block_rngs
from mdm_profiles import MissionProfile

DEFAULT_DT = 0.1


def run_reference_block(
    profile: MissionProfile,
    seed: int,
    block: int,
    n_runs: int,
    *,
    dt: float = DEFAULT_DT,
    horizon: float | None = None,
    step_every_lane: bool = True,
) -> BlockResult:
    """dt-stepped counterpart of ``engine.run_block`` (same seeding, same start positions).

    Returns per-vehicle first-confirmation times (runs, vehicles, targets), inf where a vehicle
    did not confirm a target by ``horizon`` (default: the profile's mission duration). ``events``
    counts the dt steps, ``sim_seconds`` the vehicle-seconds simulated.

    ``step_every_lane=False`` hands the policy only the lanes that have something to report
    (a contact, the waypoint reached, or the level's deadline passed). For any other lane
    ``SearchPolicy.step`` changes nothing and draws nothing, so the result is bit for bit the
    same (tests/montecarlo check it), only faster.
    """
    if not dt > 0:
        raise ValueError(f"dt must be > 0 s, got {dt}")
    end = profile.mission.duration if horizon is None else horizon
    if not end >= 0:
        raise ValueError(f"horizon must be >= 0 s, got {end}")
    scenario = Scenario.from_profile(profile)
    policy = SearchPolicy(policy_config(profile))
    rng_targets, rng_start, rng_policy = block_rngs(seed, block)
    fleet = profile.fleet
    n_vehicles = fleet.vehicles
    tracks = scenario.tracks(n_runs, rng_targets)
    start = scenario.start_positions(n_runs, n_vehicles, fleet.start, rng_start)

    n = n_runs * n_vehicles
    lanes = np.arange(n)
    run_of = np.repeat(np.arange(n_runs), n_vehicles)
    position = start.reshape(n, 2).copy()
    state = policy.start(position, np.zeros(n), rng_policy)
    velocity = pursuit_reference(position, state.waypoint, fleet.speed)
    model = LagModel(tau=fleet.tau)

    targets = scenario.targets
    m = targets.count
    real = ~targets.false_mask
    appear = targets.appear_times
    first = np.full((n, m), np.inf)
    accept2 = fleet.acceptance_radius**2

    # policy.redetection: the detection sensor read on the last level too
    redetect = (
        np.full(n, policy.config.levels[-2].sensor_radius)
        if policy.config.redetection != "ignore" and policy.n_levels > 1
        else None
    )
    detecting = np.zeros(n, dtype=bool)  # not the confirmation sensor: false targets seen
    steps = math.ceil(end / dt - 1e-9)
    for k in range(1, steps + 1):
        t = min(k * dt, end)  # k * dt, not a running sum: no drift over 10^4 steps
        step = t - (k - 1) * dt
        ref = pursuit_reference(position, state.waypoint, fleet.speed)
        position, velocity = lag_step(position, velocity, ref, step, model)
        gap = state.waypoint - position
        reached = np.einsum("nk,nk->n", gap, gap) <= accept2
        now = np.full(n, t)
        target_pos = tracks.positions(run_of, now)
        present = np.broadcast_to(appear <= t, (n, m))
        seen, _ = contacts(
            policy.sensor_radius(state),
            policy.uses_confirmation_sensor(state),
            position,
            target_pos,
            present,
            targets.false_mask,
        )
        detections = (
            contacts(redetect, detecting, position, target_pos, present, targets.false_mask)[0]
            if redetect is not None
            else None
        )
        if step_every_lane:
            idx = lanes
        else:
            idx = np.flatnonzero(seen.any(axis=1) | reached | (policy.deadline(state) <= t))
            if idx.size == 0:
                continue
        obs = Observation(
            time=now[idx],
            position=position[idx],
            reached=reached[idx],
            contacts=seen[idx],
            contact_positions=target_pos[idx],
            detections=None if detections is None else detections[idx],
        )
        outcome = policy.step(state, idx, obs, rng_policy)
        confirmed = outcome.new_confirmations & real[None, :]
        if confirmed.any():
            rows, cols = np.nonzero(confirmed)
            hit = idx[rows]
            first[hit, cols] = np.minimum(first[hit, cols], t)

    per_vehicle = first.reshape(n_runs, n_vehicles, m)
    return BlockResult(block, per_vehicle, steps, float(n * end))


def run_reference(
    profile: MissionProfile,
    *,
    runs: int,
    seed: int = 0,
    block_runs: int = 50,
    dt: float = DEFAULT_DT,
    horizon: float | None = None,
    step_every_lane: bool = True,
) -> BlockResult:
    """``runs`` reference missions in blocks seeded like ``runner.run_missions`` (one process).

    Block b holds the same targets and start positions as the engine's block b for the same seed
    and ``block_runs``. The per-vehicle times of all blocks are concatenated (first_block = 0).
    """
    if runs < 1:
        raise ValueError(f"runs must be >= 1, got {runs}")
    parts = [
        run_reference_block(profile, seed, b, min(block_runs, runs - lo), dt=dt, horizon=horizon)
        for b, lo in enumerate(range(0, runs, block_runs))
    ]
    return BlockResult(
        0,
        np.concatenate([p.per_vehicle for p in parts], axis=0),
        sum(p.events for p in parts),
        sum(p.sim_seconds for p in parts),
    )
