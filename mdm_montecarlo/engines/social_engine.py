"""Time-stepped batched missions for the social-cognitive baselines (PSO, SPSO, ARPSO) that
iterate every update interval (``policy.swarm.iteration: interval``; the default, one
iteration per waypoint, is mdm_montecarlo.engines.waypoint_swarm).

Unlike MDM, particles share state, so a run is stepped as a whole at the swarm's update interval,
batched over (runs, vehicles). One iteration (the per-particle parts are
mdm_core.search.swarm_iteration, shared with the live companion):

1. every vehicle with a best to follow (its own or one it heard of, fitness > 0) takes the PSO
   step of its variant (mdm_core.search.pso); the others fly the single-sensor exploration of
   the profile's level 1 (mdm_core.search.SearchPolicy, US with delta_1 by default; its
   waypoints drawn by the compiled draws of mdm_montecarlo.kernels.compiled_waypoints, the same numbers);
2. the step is flown as a straight segment at most speed x interval long (clipped to the area);
   a real target whose r_2 disc the segment enters is confirmed (closed form,
   mdm_core.world.first_entry_time) and becomes known to that vehicle;
3. each vehicle reads its signal sensor (exp(-d / r) within the signal radius, as
   mdm_core.world.contacts reads it) and keeps the strongest signal as its fitness (of a
   target it does not know to be confirmed, unless ``read_confirmed``); with
   ``after_confirmation: forget``, bests from targets it knows confirmed are dropped;
4. each vehicle publishes (personal best, current fitness, targets it knows confirmed); a message
   reaches each other vehicle ``message_delay`` seconds later unless lost (``message_drop``).
   A receiver keeps the last message it got from each sender.

Cost: the vehicles of a run share its targets, so target positions are read per run, once per
iteration, at the end of the step: the signal reading of that iteration and the confirmations
of the next (same positions, same time) both use them. The reading keeps every vehicle's
squared distance to its nearest real target; the confirmations look again only at the vehicles
within reach of one, and solve the closed form only for the pairs close enough to meet within
the step; strengths are computed only for the pairs within the signal radius. A delivery
touches only the runs whose message or losses changed since the last one (a few per cent of
them per iteration). All of this gives bit-for-bit the results of solving every pair and
delivering everywhere. The per-particle passes (sensing, swarm bests, the PSO rules, flight,
personal bests, SPSO's informants, redrawn only for the particles whose local best is stuck)
are compiled loops (mdm_montecarlo.kernels.swarm_kernels) doing the arithmetic and the random draws of
the numpy rules of mdm_core.search.pso and swarm_iteration in their order: the same results bit
for bit, without a (runs, vehicles, ...) temporary per operation.

When every message arrives at once and none is lost (message_delay 0, message_drop 0, the
paper's setting), what receiver i heard from sender j is sender j's own best and reading as
they stand (both are dropped by the same ``forget``: after a delivery every vehicle of a run
knows the same confirmed targets, so a delivery is each confirmation made known to its whole
run). The (runs, receivers, senders) inbox is then not kept: the heard tables are views of the
own bests and the losses' draw is skipped by advancing the generator. Same results bit for bit
as the inbox (tests/montecarlo/test_pso_engine.py compares the two).

Randomness: SeedSequence([seed, block]) as in engine.py, drawn in a fixed order over the whole
block, so results are identical for any number of workers.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mdm_core.search.from_profile import policy_config, signal_radius, swarm_config
from mdm_core.search.pso import Best, SwarmConfig, forget
from mdm_core.search.swarm_iteration import BestOf
from mdm_core.world import Scenario
from mdm_montecarlo.engines.engine import BlockResult, block_rngs, departures
from mdm_montecarlo.engines.swarm_sensors import SwarmSensors
from mdm_montecarlo.engines.waypoint_swarm import run_waypoint_swarm_block
from mdm_montecarlo.kernels import swarm_kernels as kernels
from mdm_montecarlo.kernels.compiled_tracks import shared_tracks
from mdm_montecarlo.kernels.compiled_waypoints import CompiledWaypoints
from mdm_profiles import MissionProfile

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]
SWARM_KINDS = ("pso", "spso", "arpso")


@dataclass(frozen=True)
class Message:
    """What every vehicle of a block publishes at the end of one iteration."""

    best: Best
    """(runs, vehicles) personal bests."""
    current: FloatArray
    """(runs, vehicles) fitness read this iteration."""
    known: NDArray[np.float32]
    """(runs, vehicles, targets) 1 where the sender knows the target to be confirmed, else 0
    (float32: receivers count the senders that know a target with a matrix product)."""


@dataclass
class _Inbox:
    """What every receiver of a block last heard from every sender, as (runs, receivers,
    senders) tables updated in place."""

    heard: Best
    current: FloatArray
    """Each sender's fitness read in the iteration of the message (ARPSO)."""
    last: tuple[Message, BoolArray] | None = None
    """The message delivered last and which receivers got it."""

    @classmethod
    def empty(cls, shape: tuple[int, int], n_vehicles: int) -> _Inbox:
        """Nothing heard yet: fitness 0, no source."""
        heard = Best(
            np.zeros((*shape, n_vehicles, 2)),
            np.zeros((*shape, n_vehicles)),
            np.full((*shape, n_vehicles), -1, dtype=np.intp),
        )
        return cls(heard, np.zeros((*shape, n_vehicles)))

    def deliver(self, message: Message, got: BoolArray, known: BoolArray) -> None:
        """Receiver i takes sender j's message where got[run, i, j]; the targets the senders
        know are added to ``known`` (runs, receivers, targets) in place.

        Runs whose message and losses are those of the last delivery are skipped: taking it
        again would change nothing (a best dropped by ``forget`` since stays dropped, as
        ``known`` only grows).
        """
        runs = _changed_runs(message, got, self.last)
        self.last = (message, got)
        got = got[runs]
        sent = message.best
        _take_sent(_as_complex(self.heard.position), runs, got, _as_complex(sent.position))
        _take_sent(self.heard.fitness, runs, got, sent.fitness)
        _take_sent(self.heard.source, runs, got, sent.source)
        _take_sent(self.current, runs, got, message.current)
        # How many received senders know each target (exact: small integers in float32).
        known[runs] |= np.matmul(got.astype(np.float32), message.known[runs]) > 0

    def forget(self, known: BoolArray) -> None:
        """mdm_core.search.pso.forget for the heard bests, in place: a receiver drops the
        bests whose source target it knows (``known`` (runs, receivers, targets)) to be
        confirmed. Only the bests that have a source are looked at."""
        heard = self.heard
        sourced = _nonzero(heard.source >= 0)
        kept = forget(
            Best(heard.position[sourced], heard.fitness[sourced], heard.source[sourced]),
            known[sourced[:2]],
        )
        heard.fitness[sourced] = kept.fitness
        heard.source[sourced] = kept.source


def _changed_runs(
    message: Message, got: BoolArray, last: tuple[Message, BoolArray] | None
) -> IntArray:
    """The runs whose message or losses differ from those of ``last`` (all if None)."""
    if last is None:
        return np.arange(len(got))
    before, got_before = last
    same = (
        (message.best.fitness == before.best.fitness)
        & (message.best.source == before.best.source)
        & (message.current == before.current)
        & (message.best.position == before.best.position).all(axis=-1)
        & (message.known == before.known).all(axis=-1)
    ).all(axis=-1)
    same &= (got == got_before).all(axis=(1, 2))
    return np.flatnonzero(~same)


def _take_sent(table: NDArray[Any], runs: IntArray, got: BoolArray, sent: NDArray[Any]) -> None:
    """table[run, i, j] = sent[run, j] where got (rows of ``runs``), in place."""
    table[runs] = np.where(got, sent[runs][:, None, :], table[runs])


def _nonzero(mask: BoolArray) -> tuple[IntArray, IntArray, IntArray]:
    """np.nonzero of a 3-D mask, from its flat indices (several times faster when sparse)."""
    rest, k = np.divmod(np.flatnonzero(mask), mask.shape[2])
    i, j = np.divmod(rest, mask.shape[1])
    return i, j, k


def run_swarm_block(
    profile: MissionProfile, seed: int, block: int, n_runs: int, *, keep_inbox: bool = False
) -> BlockResult:
    """Simulate ``n_runs`` missions of a pso/spso/arpso profile (block ``block`` of ``seed``).

    keep_inbox: keep the per-receiver inbox even where every message arrives at once and none
    is lost (same results, slower; the module's docstring). A swarm that iterates per waypoint
    (``policy.swarm.iteration: waypoint``) runs on mdm_montecarlo.engines.waypoint_swarm."""
    if profile.policy.swarm.iteration == "waypoint":
        return run_waypoint_swarm_block(profile, seed, block, n_runs)
    scenario = Scenario.from_profile(profile)
    config = swarm_config(profile)
    spec = profile.policy.swarm
    explorer = CompiledWaypoints(policy_config(profile))
    rng_targets, rng_start, rng = block_rngs(seed, block)
    n_vehicles = profile.fleet.vehicles
    shape = (n_runs, n_vehicles)
    n = n_runs * n_vehicles
    dt = spec.update_interval
    speed = profile.fleet.speed
    targets = scenario.targets
    real = ~targets.false_mask
    sensors = SwarmSensors(
        tracks=shared_tracks(
            scenario, n_runs, rng_targets, max(profile.mission.ts_cap, profile.mission.duration)
        ),
        runs=np.arange(n_runs),
        real=real,
        appear=targets.appear_times,
        confirm_radius=scenario.confirmation.radius,
        signal_radius=signal_radius(profile),
        dt=dt,
    )
    position = scenario.start_positions(n_runs, n_vehicles, profile.fleet.start, rng_start)
    m = targets.count
    area = np.asarray(scenario.area.size, dtype=float)

    first = np.full((*shape, m), np.inf)
    known = np.zeros((*shape, m), dtype=bool)
    # What the sensor leaves out and what the bests are forgotten by (nothing: all False).
    nothing = np.zeros_like(known)
    unread = nothing if spec.read_confirmed else known
    forget_by = known if spec.after_confirmation == "forget" else nothing
    own = Best(position.copy(), np.zeros(shape), np.full(shape, -1, dtype=np.intp))
    inbox = _Inbox.empty(shape, n_vehicles)
    # The last reading, its source and the squared distance to the nearest real target.
    current = np.zeros(shape)
    source = np.full(shape, -1, dtype=np.intp)
    nearest = np.empty(shape)
    previous_best = np.zeros(shape)
    inertia = np.full(shape, config.inertia)
    others = ~np.eye(n_vehicles, dtype=bool)
    links = np.broadcast_to(others, (*shape, n_vehicles)).copy()
    if config.variant == "spso":
        links = _random_informants(rng, n_runs, n_vehicles, spec.informants)
    delay = round(spec.message_delay / dt)
    outbox: deque[Message] = deque(maxlen=delay + 1)
    broadcast = delay == 0 and spec.message_drop == 0.0 and not keep_inbox
    best_of: BestOf = _swarm_best
    # The tables below are updated in place: these are read every iteration.
    heard, heard_current = inbox.heard, inbox.current
    if broadcast:
        best_of = _best_of_linked_peers if config.variant == "spso" else _best_of_all_peers
        heard, heard_current = _heard_from_own(own), _to_every_receiver(current)

    waypoint = explorer.explore(position.reshape(n, 2), rng).reshape(*shape, 2)
    targets_now = sensors.motion(0.0)
    # Only the distances: the first reading is taken after the first step.
    everyone = np.ones(shape, dtype=bool)
    sensors.sense(targets_now, position, unread, everyone, np.zeros(shape), source, nearest)
    step = np.zeros((*shape, 2))
    guided = np.zeros(shape, dtype=bool)
    # SPSO: the swarm bests the informants' refresh found for the next iteration.
    social: tuple[Best, BoolArray] | None = None
    social_fitness = np.zeros(shape)
    stop = max(profile.mission.ts_cap, profile.mission.duration)
    duration = profile.mission.duration
    t = 0.0
    steps = 0
    followed = 0

    while t < stop - 1e-9:
        # mdm_core.search.swarm_iteration.choose_move, then the flight clipped to the area.
        best, own_is_social = best_of(own, heard, links) if social is None else social
        follow = best.fitness > 0
        if config.variant == "arpso":
            inertia = kernels.arpso_inertia(
                previous_best,
                own.fitness,
                current,
                heard_current,
                links,
                config.arpso_initial_inertia,
                config.arpso_speed_weight,
                config.arpso_aggregation_weight,
            )
        swarm_move = _next_step(config, step, position, own, best, own_is_social, inertia, rng)
        # Particles that lost their best go back to exploring from where they are.
        lost = guided & ~follow
        if lost.any():
            waypoint[lost] = explorer.explore(position[lost], rng)
        new_position, step, reached, longest = kernels.fly(
            position, swarm_move, follow, waypoint, speed * dt, area
        )
        guided = follow
        followed += int(np.count_nonzero(follow & ~own_is_social))

        # Confirmations along the straight segment flown in this iteration.
        confirmed = sensors.confirm(targets_now, position, nearest, step, longest, first, known)
        position = new_position
        t += dt
        steps += 1

        if reached.any():
            waypoint[reached] = explorer.explore(position[reached], rng)

        # Fitness: the signal sensor, targets known to be confirmed left out.
        targets_now = sensors.motion(t)
        sensors.sense(targets_now, position, unread, everyone, current, source, nearest)
        previous_best = kernels.read_into_best(
            own.position, own.fitness, own.source, forget_by, position, current, source
        )

        if broadcast:
            # The losses are drawn every iteration, so the random stream does not depend on
            # delay or drop; with drop 0 none is lost and the numbers are not needed.
            _skip_uniforms(rng, n * n_vehicles)
            # Every vehicle of a run knew the same targets before this iteration's
            # confirmations (the last share): each is now known to the whole run.
            run, index = confirmed
            known[run, :, index] = True
        else:
            outbox.append(Message(own.copy(), current.copy(), known.astype(np.float32)))
            got = (rng.random((*shape, n_vehicles)) >= spec.message_drop) & others
            if len(outbox) > delay:
                inbox.deliver(outbox[0], got, known)
        kernels.forget_known(own.fitness, own.source, forget_by)
        if not broadcast:
            inbox.forget(forget_by)
        if config.variant == "spso":
            social, social_fitness = _refresh_informants(
                rng, own, heard, links, social_fitness, best_of, spec.informants
            )
        if t >= duration and _all_confirmed(first, real):
            break

    gone = departures(profile, sensors.tracks, max(profile.mission.ts_cap, duration))
    return BlockResult(block, first, steps * n, float(t * n), followed, gone)


def _skip_uniforms(rng: np.random.Generator, count: int) -> None:
    """Move ``rng`` past ``count`` numbers of random(): PCG64 (default_rng) makes each from
    one 64-bit output, so it jumps ahead without drawing them (these engines draw nothing
    narrower, which would leave a buffered half behind)."""
    bits = rng.bit_generator
    if isinstance(bits, np.random.PCG64):
        bits.advance(count)
    else:
        rng.random(count)


def _to_every_receiver(values: NDArray[Any]) -> NDArray[Any]:
    """(runs, senders, ...) as every receiver holds them: (runs, receivers, senders, ...), a
    view."""
    n = values.shape[1]
    return np.broadcast_to(values[:, None], (values.shape[0], n, *values.shape[1:]))


def _heard_from_own(own: Best) -> Best:
    """The inbox's heard bests when every message arrives at once: each sender's own best."""
    return Best(
        _to_every_receiver(own.position),
        _to_every_receiver(own.fitness),
        _to_every_receiver(own.source),
    )


def _swarm_best(own: Best, heard: Best, links: BoolArray) -> tuple[Best, BoolArray]:
    """mdm_core.search.pso.swarm_best, compiled (mdm_montecarlo.kernels.swarm_kernels.swarm_best)."""
    return _as_best(
        kernels.swarm_best(
            own.position,
            own.fitness,
            own.source,
            heard.position,
            heard.fitness,
            heard.source,
            links,
        )
    )


def _best_of_all_peers(own: Best, heard: Best, links: BoolArray) -> tuple[Best, BoolArray]:
    """_swarm_best for heard = _heard_from_own(own) and links to every other vehicle (PSO,
    ARPSO with every message delivered), from the run's first best
    (mdm_montecarlo.kernels.swarm_kernels.best_of_all_peers)."""
    return _as_best(kernels.best_of_all_peers(own.position, own.fitness, own.source))


def _best_of_linked_peers(own: Best, heard: Best, links: BoolArray) -> tuple[Best, BoolArray]:
    """_swarm_best for heard = _heard_from_own(own) (SPSO with every message delivered)
    (mdm_montecarlo.kernels.swarm_kernels.best_of_linked_peers)."""
    return _as_best(kernels.best_of_linked_peers(own.position, own.fitness, own.source, links))


def _as_best(
    found: tuple[FloatArray, FloatArray, IntArray, BoolArray],
) -> tuple[Best, BoolArray]:
    """A swarm-best kernel's (position, fitness, source, mine) as (Best, mine)."""
    position, fitness, source, mine = found
    return Best(position, fitness, source), mine


def _next_step(
    config: SwarmConfig,
    step: FloatArray,
    position: FloatArray,
    own: Best,
    social: Best,
    own_is_social: BoolArray,
    inertia: FloatArray,
    rng: np.random.Generator,
) -> FloatArray:
    """mdm_core.search.pso.next_step, compiled; ``inertia`` (runs, vehicles) is the PSO
    weight for every particle or ARPSO's per-particle one."""
    if config.variant == "spso":
        direction = rng.standard_normal(position.shape)
        uniform = rng.random(position.shape[:-1])
        return kernels.spso_steps(
            step,
            position,
            own.position,
            own.fitness,
            social.position,
            social.fitness,
            own_is_social,
            config.spso_inertia,
            config.spso_acceleration,
            direction,
            uniform,
            config.max_step,
            config.constant_speed,
        )
    return kernels.pso_steps(
        step,
        position,
        own.position,
        own.fitness,
        social.position,
        social.fitness,
        inertia,
        config.cognitive,
        config.social,
        rng.random((2, *position.shape)),
        config.max_step,
        config.constant_speed,
    )


def _random_informants(rng: np.random.Generator, runs: int, n: int, k: int) -> BoolArray:
    """mdm_core.search.pso.random_informants for (runs,), compiled."""
    return kernels.informants(rng.random((runs, n, n)), k)


def _refresh_informants(
    rng: np.random.Generator,
    own: Best,
    heard: Best,
    links: BoolArray,
    local_fitness: FloatArray,
    best_of: BestOf,
    k: int,
) -> tuple[tuple[Best, BoolArray], FloatArray]:
    """mdm_core.search.swarm_iteration.refresh_informants with ``links`` updated in place (the
    same draw; only the stuck particles' rows are computed: swarm_kernels.relink). Returns
    best_of's answer over the new links (the next iteration's: nothing changes the bests
    before it; only the stuck particles' is found again) and the local bests' fitness to
    compare with next time."""
    updated, mine = best_of(own, heard, links)
    fitness = updated.fitness.copy()
    stuck = fitness <= local_fitness
    if stuck.any():
        kernels.relink(rng.random(links.shape), stuck, k, links)
        kernels.update_swarm_best(
            own.position,
            own.fitness,
            own.source,
            heard.position,
            heard.fitness,
            heard.source,
            links,
            stuck,
            updated.position,
            updated.fitness,
            updated.source,
            mine,
        )
    return (updated, mine), fitness


def _as_complex(points: FloatArray) -> NDArray[np.complex128]:
    """Points (..., 2) as one complex number each (a view), so that a selection moves both
    coordinates at once."""
    return points.view(np.complex128)[..., 0]


def _all_confirmed(first: FloatArray, real: BoolArray) -> bool:
    team = first.min(axis=1)[:, real]
    return bool(np.isfinite(team).all())
