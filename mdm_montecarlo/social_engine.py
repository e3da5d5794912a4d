"""Time-stepped batched missions for the social-cognitive baselines (PSO, SPSO, ARPSO).

Unlike MDM, particles share state, so a run is stepped as a whole at the swarm's update interval,
batched over (runs, vehicles). One iteration (the per-particle parts are
companion.search.swarm_iteration, shared with the live companion):

1. every vehicle with a best to follow (its own or one it heard of, fitness > 0) takes the PSO
   step of its variant (companion.search.pso); the others fly the single-sensor exploration of
   the profile's level 1 (companion.search.SearchPolicy, US with delta_1 by default);
2. the step is flown as a straight segment at most speed x interval long (clipped to the area);
   a real target whose r_2 disc the segment enters is confirmed (closed form,
   sim_vehicle_stub.world.first_entry_time) and becomes known to that vehicle;
3. each vehicle reads its signal sensor (sim_vehicle_stub.world.contacts, exp(-d / r) within the
   signal radius) and keeps the strongest signal of a target it does not know to be confirmed
   as its fitness; personal bests from confirmed targets are forgotten;
4. each vehicle publishes (personal best, current fitness, targets it knows confirmed); a message
   reaches each other vehicle ``message_delay`` seconds later unless lost (``message_drop``).
   A receiver keeps the last message it got from each sender.

Randomness: SeedSequence([seed, block]) as in engine.py, drawn in a fixed order over the whole
block, so results are identical for any number of workers.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from companion.search import SearchPolicy
from companion.search.from_profile import policy_config, swarm_config
from companion.search.pso import Best, forget, random_informants, signal_fitness
from companion.search.swarm_iteration import (
    choose_move,
    explore,
    read_into_best,
    refresh_informants,
)
from mdm_montecarlo.engine import BlockResult, block_rngs
from mdm_profiles import MissionProfile
from sim_vehicle_stub.world import Scenario, contacts, first_entry_time

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
SWARM_KINDS = ("pso", "spso", "arpso")


@dataclass(frozen=True)
class Message:
    """What every vehicle of a block publishes at the end of one iteration."""

    best: Best
    """(runs, vehicles) personal bests."""
    current: FloatArray
    """(runs, vehicles) fitness read this iteration."""
    known: BoolArray
    """(runs, vehicles, targets) targets the sender knows to be confirmed."""


def run_swarm_block(profile: MissionProfile, seed: int, block: int, n_runs: int) -> BlockResult:
    """Simulate ``n_runs`` missions of a pso/spso/arpso profile (block ``block`` of ``seed``)."""
    scenario = Scenario.from_profile(profile)
    config = swarm_config(profile)
    spec = profile.policy.swarm
    explorer = SearchPolicy(policy_config(profile))
    rng_targets, rng_start, rng = block_rngs(seed, block)
    n_vehicles = profile.fleet.vehicles
    shape = (n_runs, n_vehicles)
    n = n_runs * n_vehicles
    dt = spec.update_interval
    speed = profile.fleet.speed
    tracks = scenario.tracks(n_runs, rng_targets)
    position = scenario.start_positions(n_runs, n_vehicles, profile.fleet.start, rng_start)
    lanes_run = np.repeat(np.arange(n_runs), n_vehicles)

    targets = scenario.targets
    m = targets.count
    real = ~targets.false_mask
    appear = targets.appear_times
    area = scenario.area.size
    r_confirm = np.full(n, scenario.confirmation.radius)
    r_signal = np.full(n, spec.signal_radius)
    no_confirm = np.zeros(n, dtype=bool)

    first = np.full((*shape, m), np.inf)
    known = np.zeros((*shape, m), dtype=bool)
    own = Best(position.copy(), np.zeros(shape), np.full(shape, -1, dtype=np.intp))
    heard = Best(
        np.zeros((*shape, n_vehicles, 2)),
        np.zeros((*shape, n_vehicles)),
        np.full((*shape, n_vehicles), -1, dtype=np.intp),
    )
    heard_current = np.zeros((*shape, n_vehicles))
    current = np.zeros(shape)
    previous_best = np.zeros(shape)
    others = ~np.eye(n_vehicles, dtype=bool)
    links = np.broadcast_to(others, (*shape, n_vehicles)).copy()
    if config.variant == "spso":
        links = random_informants(rng, (n_runs,), n_vehicles, spec.informants)
    delay = round(spec.message_delay / dt)
    outbox: deque[Message] = deque(maxlen=delay + 1)

    waypoint = explore(explorer, position.reshape(n, 2), rng).reshape(*shape, 2)
    step = np.zeros((*shape, 2))
    guided = np.zeros(shape, dtype=bool)
    social_fitness = np.zeros(shape)
    stop = max(profile.mission.ts_cap, profile.mission.duration)
    duration = profile.mission.duration
    t = 0.0
    steps = 0

    while t < stop - 1e-9:
        move, follow, _ = choose_move(
            config,
            explorer,
            position=position,
            step=step,
            waypoint=waypoint,
            guided=guided,
            own=own,
            heard=heard,
            heard_current=heard_current,
            current=current,
            previous_best=previous_best,
            links=links,
            distance=speed * dt,
            rng=rng,
        )
        new_position = np.clip(position + move, 0.0, area)
        step = new_position - position
        guided = follow

        # Confirmations along the straight segment flown in this iteration.
        target_pos, target_vel = tracks.motion(lanes_run, np.full(n, t))
        eligible = real[None, :] & ~known.reshape(n, m)
        entry = first_entry_time(
            position.reshape(n, 2),
            step.reshape(n, 2) / dt,
            np.full(n, dt),
            target_pos,
            target_vel,
            r_confirm,
            eligible,
            appear[None, :] - t,
        ).reshape(*shape, m)
        hit = entry <= dt
        first = np.where(hit, np.minimum(first, t + entry), first)
        known |= hit
        position = new_position
        t += dt
        steps += 1

        reached = ~follow & (np.linalg.norm(waypoint - position, axis=-1) <= 1e-6)
        if reached.any():
            waypoint[reached] = explore(explorer, position[reached], rng)

        # Fitness: the signal sensor, targets known to be confirmed left out.
        now = np.full(n, t)
        present = np.broadcast_to(appear[None, :] <= t, (n, m))
        within, strength = contacts(
            r_signal,
            no_confirm,
            position.reshape(n, 2),
            tracks.positions(lanes_run, now),
            present,
            targets.false_mask,
        )
        current, source = signal_fitness(
            strength.reshape(*shape, m), within.reshape(*shape, m) & ~known
        )
        own, previous_best = read_into_best(own, known, position, current, source)

        outbox.append(Message(own.copy(), current.copy(), known.copy()))
        # Drawn every iteration, so the random stream does not depend on delay or drop.
        got = (rng.random((*shape, n_vehicles)) >= spec.message_drop) & others
        if len(outbox) > delay:
            heard, heard_current, known = _deliver(outbox[0], heard, heard_current, known, got)
        own = forget(own, known)
        heard = forget(heard, np.broadcast_to(known[:, :, None, :], (*shape, n_vehicles, m)))
        if config.variant == "spso":
            links, social_fitness = refresh_informants(
                own,
                heard,
                links,
                social_fitness,
                lambda: random_informants(rng, (n_runs,), n_vehicles, spec.informants),
            )
        if t >= duration and _all_confirmed(first, real):
            break

    return BlockResult(block, first, steps * n, float(t * n))


def _deliver(
    message: Message, heard: Best, heard_current: FloatArray, known: BoolArray, got: BoolArray
) -> tuple[Best, FloatArray, BoolArray]:
    """Receiver i takes sender j's message where got[run, i, j].

    Returns what every receiver has heard from every sender and the targets it now knows.
    """
    sent = message.best
    gotp = got[..., None]
    heard = Best(
        np.where(gotp, sent.position[:, None, :, :], heard.position),
        np.where(got, sent.fitness[:, None, :], heard.fitness),
        np.where(got, sent.source[:, None, :], heard.source).astype(np.intp),
    )
    heard_current = np.where(got, message.current[:, None, :], heard_current)
    known = known | np.any(got[..., None] & message.known[:, None, :, :], axis=2)
    return heard, heard_current, known


def _all_confirmed(first: FloatArray, real: BoolArray) -> bool:
    team = first.min(axis=1)[:, real]
    return bool(np.isfinite(team).all())
