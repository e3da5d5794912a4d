"""The compiled pieces of the swarm engine (mdm_montecarlo.kernels.swarm_kernels) against the numpy
rules they replace, bit for bit, on random states (ties, zero fitness, every branch)."""

from __future__ import annotations

import numpy as np
import pytest

from mdm_core import libm
from mdm_core.search.planar import length as _length
from mdm_core.search.pso import (
    Best,
    SwarmConfig,
    Variant,
    forget,
    next_step,
    random_informants,
    signal_fitness,
    swarm_best,
)
from mdm_core.search.swarm_iteration import arpso_weights, read_into_best, refresh_informants
from mdm_core.world.sensors import THRESHOLD
from mdm_montecarlo.engines.social_engine import _refresh_informants, _swarm_best
from mdm_montecarlo.kernels import swarm_kernels as kernels

RUNS, N, M = 40, 7, 5


def _state(seed: int) -> tuple[np.random.Generator, Best, np.ndarray, np.ndarray]:
    """A random generator, personal bests (fitness 0 in about a quarter, ties between the
    others), positions (RUNS, N, 2) and known (RUNS, N, M)."""
    rng = np.random.default_rng(seed)
    fitness = rng.integers(0, 4, (RUNS, N)) / 4.0
    source = np.where(fitness > 0, rng.integers(0, M, (RUNS, N)), -1).astype(np.intp)
    own = Best(rng.uniform(0, 1000, (RUNS, N, 2)), fitness, source)
    return rng, own, rng.uniform(0, 1000, (RUNS, N, 2)), rng.random((RUNS, N, M)) < 0.3


def _same(a: np.ndarray, b: np.ndarray) -> None:
    assert a.dtype == b.dtype
    assert a.shape == b.shape
    assert a.tobytes() == b.tobytes()


def _same_best(a: Best, b: Best) -> None:
    for x, y in zip(
        (a.position, a.fitness, a.source), (b.position, b.fitness, b.source), strict=True
    ):
        _same(np.asarray(x), np.asarray(y))


def _heard_from_own(own: Best) -> Best:
    """The engine's views when every message arrives at once: each sender's own best."""
    return Best(
        np.broadcast_to(own.position[:, None], (RUNS, N, N, 2)),
        np.broadcast_to(own.fitness[:, None], (RUNS, N, N)),
        np.broadcast_to(own.source[:, None], (RUNS, N, N)),
    )


@pytest.mark.parametrize("seed", range(3))
def test_sense_is_signal_fitness_and_the_nearest_real_target(seed: int) -> None:
    rng, _, position, known = _state(seed)
    target = rng.uniform(0, 1000, (RUNS, M, 2))
    radius, t = 300.0, 20.0
    appear = np.array([0.0, t, 50.0, 0.0, t])
    real = np.array([True, True, False, True, False])
    fitness, nearest = np.empty((RUNS, N)), np.empty((RUNS, N))
    source = np.empty((RUNS, N), dtype=np.intp)
    kernels.sense(
        target,
        position,
        appear,
        t,
        radius,
        radius * radius * (1 + 1e-9),
        known,
        real,
        np.ones((RUNS, N), dtype=bool),
        fitness,
        source,
        nearest,
    )
    dx = target[:, None, :, 0] - position[:, :, None, 0]
    dy = target[:, None, :, 1] - position[:, :, None, 1]
    gaps = dx * dx + dy * dy
    _same(nearest, gaps[..., real].min(axis=-1))
    distance = np.sqrt(gaps)
    # The kernel's exp is the C library's (numpy's AVX-512 exp rounds some last bits otherwise).
    strength = libm.exp(-distance / radius)
    usable = (distance < radius) & (strength > THRESHOLD) & (appear <= t) & ~known
    want_fitness, want_source = signal_fitness(strength, usable)
    assert (want_fitness > 0).any()
    _same(fitness, want_fitness)
    _same(source, want_source)


def test_open_pairs_are_the_near_unknown_real_pairs() -> None:
    rng, _, position, known = _state(3)
    target = rng.uniform(0, 1000, (RUNS, M, 2))
    real = rng.random(M) < 0.7
    dx = target[:, None, :, 0] - position[:, :, None, 0]
    dy = target[:, None, :, 1] - position[:, :, None, 1]
    gaps = dx * dx + dy * dy
    reach2 = 200.0**2
    nearest = np.where(real, gaps, np.inf).min(axis=-1)
    got = kernels.open_pairs(target, position, nearest, reach2, real, known)
    want = np.nonzero((gaps <= reach2) & real & ~known)
    assert len(want[0]) > 10
    for a, b in zip(got, want, strict=True):
        _same(a, b.astype(np.intp))


def test_bests_are_forgotten_and_improved() -> None:
    rng, own, position, known = _state(4)
    forgotten = own.copy()
    kernels.forget_known(forgotten.fitness, forgotten.source, known)
    _same_best(forgotten, forget(own, known))

    reading = rng.integers(0, 4, (RUNS, N)) / 4.0
    source = np.where(reading > 0, rng.integers(0, M, (RUNS, N)), -1).astype(np.intp)
    want, want_previous = read_into_best(own, known, position, reading, source)
    got = own.copy()
    previous = kernels.read_into_best(
        got.position, got.fitness, got.source, known, position, reading, source
    )
    _same_best(got, want)
    _same(previous, want_previous)


@pytest.mark.parametrize("broadcast", [False, True])
def test_swarm_best_is_the_numpy_rule(broadcast: bool) -> None:
    rng, own, _, _ = _state(5)
    links = rng.random((RUNS, N, N)) < 0.5
    if broadcast:
        heard = _heard_from_own(own)
    else:
        heard = Best(
            rng.uniform(0, 1000, (RUNS, N, N, 2)),
            rng.integers(0, 4, (RUNS, N, N)) / 4.0,
            rng.integers(-1, M, (RUNS, N, N)).astype(np.intp),
        )
    want, want_mine = swarm_best(own, heard, links)
    position, fitness, source, mine = kernels.swarm_best(
        own.position, own.fitness, own.source, heard.position, heard.fitness, heard.source, links
    )
    _same_best(Best(position, fitness, source), want)
    _same(mine, want_mine)
    assert want_mine.any()
    assert not want_mine.all()


@pytest.mark.parametrize("share", [0.0, 0.25, 1.0])
def test_best_of_linked_peers_is_swarm_best_over_the_heard_own_bests(share: float) -> None:
    _, own, _, _ = _state(7)  # fitness in quarters: ties between senders everywhere
    links = np.random.default_rng(8).random((RUNS, N, N)) < share
    heard = _heard_from_own(own)
    want, want_mine = swarm_best(own, heard, links)
    position, fitness, source, mine = kernels.best_of_linked_peers(
        own.position, own.fitness, own.source, links
    )
    _same_best(Best(position, fitness, source), want)
    _same(mine, want_mine)
    assert want_mine.all() == (share == 0.0)


def test_best_of_all_peers_is_swarm_best_over_every_other_vehicle() -> None:
    _, own, _, _ = _state(6)
    own.fitness[:3] = 0.5  # whole runs tied, and runs where the first best is not vehicle 0
    own.fitness[3, 4] = 1.0
    heard = _heard_from_own(own)
    others = np.broadcast_to(~np.eye(N, dtype=bool), (RUNS, N, N))
    want, want_mine = swarm_best(own, heard, others)
    position, fitness, source, mine = kernels.best_of_all_peers(
        own.position, own.fitness, own.source
    )
    _same_best(Best(position, fitness, source), want)
    _same(mine, want_mine)
    assert want_mine[:3].all()
    assert not want_mine[3].all()


def test_arpso_inertia_is_arpso_weights() -> None:
    rng, own, _, _ = _state(7)
    config = SwarmConfig("arpso", max_step=100.0)
    current = rng.random((RUNS, N)) * (rng.random((RUNS, N)) < 0.6)
    heard_current = rng.random((RUNS, N, N)) * 1e-3 ** rng.integers(0, 3, (RUNS, N, N))
    previous = own.fitness * rng.random((RUNS, N))
    links = rng.random((RUNS, N, N)) < 0.8
    want = arpso_weights(config, previous, own, current, heard_current, links)
    got = kernels.arpso_inertia(
        previous,
        own.fitness,
        current,
        heard_current,
        links,
        config.arpso_initial_inertia,
        config.arpso_speed_weight,
        config.arpso_aggregation_weight,
    )
    assert want is not None
    _same(got, want)


@pytest.mark.parametrize("size", [0, 1, 7, 8, 13, 127, 128, 129, 300, 1031, 5000])
def test_pairwise_sum_is_numpy_sum(size: int) -> None:
    rng = np.random.default_rng(size)
    values = rng.random(size) * 10.0 ** rng.integers(-8, 8, size)
    assert kernels._pairwise_sum(values) == values.sum()


@pytest.mark.parametrize("variant", ["pso", "spso", "arpso"])
@pytest.mark.parametrize("constant_speed", [True, False])
def test_steps_are_next_step(variant: Variant, constant_speed: bool) -> None:
    rng, own, position, _ = _state(8)
    social = Best(
        rng.uniform(0, 1000, (RUNS, N, 2)), rng.integers(0, 3, (RUNS, N)) / 2.0, own.source
    )
    own_is_social = rng.random((RUNS, N)) < 0.5
    step = rng.normal(0, 30, (RUNS, N, 2))
    step[0, 0] = 0.0
    config = SwarmConfig(variant, max_step=40.0, constant_speed=constant_speed)
    inertia = rng.uniform(0.3, 1.2, (RUNS, N))
    draws = np.random.default_rng(9)
    want = next_step(config, step, position, own, social, own_is_social, inertia, draws)
    mine = np.random.default_rng(9)
    if variant == "spso":
        direction = mine.standard_normal((RUNS, N, 2))
        uniform = mine.random((RUNS, N))
        got = kernels.spso_steps(
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
    else:
        weight = inertia if variant == "arpso" else np.full((RUNS, N), config.inertia)
        got = kernels.pso_steps(
            step,
            position,
            own.position,
            own.fitness,
            social.position,
            social.fitness,
            weight,
            config.cognitive,
            config.social,
            mine.random((2, RUNS, N, 2)),
            config.max_step,
            config.constant_speed,
        )
    _same(got, want)
    assert mine.random() == draws.random()


def test_fly_is_the_exploration_move_clipped_to_the_area() -> None:
    rng, _, position, _ = _state(10)
    area = np.array([1000.0, 800.0])
    swarm_move = rng.normal(0, 60, (RUNS, N, 2))
    follow = rng.random((RUNS, N)) < 0.5
    waypoint = position + rng.normal(0, 30, (RUNS, N, 2))
    waypoint[:, :3] = position[:, :3] + rng.normal(0, 5, (RUNS, 3, 2))
    distance = 20.0
    to_waypoint = waypoint - position
    gap = _length(to_waypoint)[..., None]
    explore_move = to_waypoint * np.minimum(1.0, distance / np.maximum(gap, 1e-12))
    move = np.where(follow[..., None], swarm_move, explore_move)
    want_position = np.clip(position + move, 0.0, area)
    want_reached = ~follow & (_length(waypoint - want_position) <= 1e-6)
    new_position, step, reached, longest = kernels.fly(
        position, swarm_move, follow, waypoint, distance, area
    )
    _same(new_position, want_position)
    _same(step, want_position - position)
    assert longest == np.abs(want_position - position).max()
    _same(reached, want_reached)
    assert want_reached.any()
    assert (want_position == 0.0).any()


@pytest.mark.parametrize("k", [0, 1, 3, N - 1, N + 2])
def test_random_informants_are_the_numpy_draw(k: int) -> None:
    mine, theirs = np.random.default_rng(k), np.random.default_rng(k)
    _same(
        kernels.informants(mine.random((RUNS, N, N)), k), random_informants(theirs, (RUNS,), N, k)
    )
    assert mine.random() == theirs.random()


@pytest.mark.parametrize("k", [1, 3])
def test_informants_with_tied_keys_are_the_partition_rule(k: int) -> None:
    """Keys on a coarse grid tie often: the links are still those at or below the k-th
    smallest key, as numpy's partition finds it (mdm_core.search.pso.random_informants)."""
    keys = np.round(np.random.default_rng(k).random((RUNS, N, N)), 1)
    want = keys.copy()
    want[..., np.arange(N), np.arange(N)] = np.inf
    kth = np.partition(want, k - 1, axis=-1)[..., k - 1, None]
    got = kernels.informants(keys, k)
    _same(got, want <= kth)
    assert (got.sum(axis=-1) > k).any()  # ties linked more than k somewhere


def test_relink_redraws_the_rows_of_the_stuck_particles() -> None:
    rng = np.random.default_rng(12)
    links = rng.random((RUNS, N, N)) < 0.5
    keys = rng.random((RUNS, N, N))
    stuck = rng.random((RUNS, N)) < 0.4
    want = np.where(stuck[..., None], kernels.informants(keys.copy(), 3), links)
    kernels.relink(keys, stuck, 3, links)
    _same(links, want)


def test_update_swarm_best_redoes_the_chosen_rows() -> None:
    rng, own, _, _ = _state(13)
    links = rng.random((RUNS, N, N)) < 0.5
    heard = _heard_from_own(own)
    found = kernels.swarm_best(
        own.position, own.fitness, own.source, heard.position, heard.fitness, heard.source, links
    )
    rows = rng.random((RUNS, N)) < 0.4
    links[rows] = rng.random((int(rows.sum()), N)) < 0.5
    want = kernels.swarm_best(
        own.position, own.fitness, own.source, heard.position, heard.fitness, heard.source, links
    )
    position, fitness, source, mine = found
    position, fitness, source, mine = position.copy(), fitness.copy(), source.copy(), mine.copy()
    kernels.update_swarm_best(
        own.position,
        own.fitness,
        own.source,
        heard.position,
        heard.fitness,
        heard.source,
        links,
        rows,
        position,
        fitness,
        source,
        mine,
    )
    for a, b in zip((position, fitness, source, mine), want, strict=True):
        _same(a, b)


@pytest.mark.parametrize("seed", range(3))
def test_refresh_informants_in_place_is_the_companions_rule(seed: int) -> None:
    """The engine's in-place refresh (social_engine._refresh_informants) and the companion's
    (swarm_iteration.refresh_informants) give the same links, fitness and random stream, and
    the best the engine carries over is swarm_best over the new links."""
    rng, own, _, _ = _state(20 + seed)
    heard = _heard_from_own(own)
    links = rng.random((RUNS, N, N)) < 0.5
    local = rng.integers(0, 4, (RUNS, N)) / 4.0
    mine, theirs = np.random.default_rng(seed), np.random.default_rng(seed)
    want_links, want_fitness = refresh_informants(
        own, heard, links.copy(), local, lambda: random_informants(theirs, (RUNS,), N, 3)
    )
    got_links = links.copy()
    (best, best_mine), got_fitness = _refresh_informants(
        mine, own, heard, got_links, local, _swarm_best, 3
    )
    _same(got_links, want_links)
    _same(got_fitness, want_fitness)
    want_best, want_mine = swarm_best(own, heard, want_links)
    _same_best(best, want_best)
    _same(best_mine, want_mine)
    assert mine.random() == theirs.random()
    assert (want_links != links).any()  # some particles were stuck and relinked


def test_sense_reads_only_the_rows_asked_and_every_nearest_distance() -> None:
    rng, _, position, known = _state(4)
    target = rng.uniform(0, 1000, (RUNS, M, 2))
    appear = np.zeros(M)
    real = np.array([True, False, True, True, True])
    radius, near = 300.0, 300.0 * 300.0 * (1 + 1e-9)

    def sensed(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        fitness, nearest = np.full((RUNS, N), -5.0), np.empty((RUNS, N))
        source = np.full((RUNS, N), -5, dtype=np.intp)
        kernels.sense(
            target, position, appear, 0.0, radius, near, known, real, rows, fitness, source, nearest
        )
        return fitness, source, nearest

    rows = rng.random((RUNS, N)) < 0.3
    every_fitness, every_source, every_nearest = sensed(np.ones((RUNS, N), dtype=bool))
    fitness, source, nearest = sensed(rows)

    assert (every_fitness[rows] > 0).any()
    _same(fitness[rows], every_fitness[rows])
    _same(source[rows], every_source[rows])
    assert (fitness[~rows] == -5.0).all()
    assert (source[~rows] == -5).all()
    _same(nearest, every_nearest)
