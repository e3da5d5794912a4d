"""Update rules of the social-cognitive baselines (mdm_core.search.pso)."""

from __future__ import annotations

import numpy as np
import pytest

from mdm_core.search.pso import (
    Best,
    SwarmConfig,
    arpso_inertia,
    clamp,
    forget,
    improve,
    next_step,
    random_informants,
    signal_fitness,
    swarm_best,
)

TARGET = np.array([5000.0, 5000.0])
RADIUS = 2000.0


def _read(position: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One target at TARGET: strength exp(-d / r) within r, as the world's sensor."""
    d = np.linalg.norm(position - TARGET, axis=-1)
    return signal_fitness(np.exp(-d / RADIUS)[..., None], (d < RADIUS)[..., None])


def test_clamp_keeps_direction_and_bounds_length() -> None:
    steps = np.array([[300.0, 400.0], [3.0, 4.0], [0.0, 0.0]])
    clamped = clamp(steps, 100.0)
    assert np.allclose(np.linalg.norm(clamped, axis=1), [100.0, 5.0, 0.0])
    assert np.allclose(clamped[0], [60.0, 80.0])
    flown = clamp(steps, 100.0, constant_speed=True)
    assert np.allclose(np.linalg.norm(flown, axis=1), [100.0, 100.0, 0.0])
    assert np.allclose(flown[1], [60.0, 80.0])


@pytest.mark.parametrize("variant", ["pso", "spso", "arpso"])
def test_every_step_is_clamped(variant: str) -> None:
    rng = np.random.default_rng(1)
    n = 500
    config = SwarmConfig(variant=variant, max_step=100.0, constant_speed=False)  # type: ignore[arg-type]
    position = rng.uniform(0, 20000, (n, 2))
    personal = Best(rng.uniform(0, 20000, (n, 2)), np.full(n, 0.5), np.zeros(n, dtype=np.intp))
    social = Best(rng.uniform(0, 20000, (n, 2)), np.full(n, 0.9), np.zeros(n, dtype=np.intp))
    step = rng.normal(0, 5000, (n, 2))
    out = next_step(
        config, step, position, personal, social, np.zeros(n, bool), np.full(n, 1.2), rng
    )
    length = np.linalg.norm(out, axis=1)
    assert length.max() <= 100.0 + 1e-9
    assert length.max() > 99.0  # far bests: steps hit the clamp


def test_signal_fitness_picks_strongest_usable_target() -> None:
    strength = np.array([[0.2, 0.9, 0.5], [0.2, 0.9, 0.5], [0.1, 0.1, 0.1]])
    usable = np.array([[True, True, True], [True, False, True], [False, False, False]])
    fit, src = signal_fitness(strength, usable)
    assert np.allclose(fit, [0.9, 0.5, 0.0])
    assert src.tolist() == [1, 2, -1]


def test_confirmed_target_leaves_the_fitness() -> None:
    best = Best(np.array([[1.0, 1.0], [2.0, 2.0]]), np.array([0.8, 0.6]), np.array([0, 1]))
    known = np.array([[True, False], [True, False]])
    out = forget(best, known)
    assert out.fitness.tolist() == [0.0, 0.6]
    assert out.source.tolist() == [-1, 1]
    # A reading that is better replaces the best; equal or worse does not.
    improved = improve(
        out, np.array([[9.0, 9.0], [8.0, 8.0]]), np.array([0.1, 0.6]), np.array([1, 0])
    )
    assert improved.fitness.tolist() == [0.1, 0.6]
    assert improved.position[1].tolist() == [2.0, 2.0]


def test_swarm_best_respects_links_and_prefers_own_on_ties() -> None:
    own = Best(np.zeros((2, 2)), np.array([0.5, 0.5]), np.array([0, 0]))
    heard = Best(
        np.array([[[1.0, 1.0], [2.0, 2.0]], [[3.0, 3.0], [4.0, 4.0]]]),
        np.array([[0.9, 0.7], [0.5, 0.4]]),
        np.array([[1, 2], [3, 4]]),
    )
    links = np.array([[False, True], [True, True]])
    best, mine = swarm_best(own, heard, links)
    assert best.fitness.tolist() == [0.7, 0.5]
    assert best.position[0].tolist() == [2.0, 2.0]
    assert mine.tolist() == [False, True]


def test_random_informants_have_k_links_and_none_to_self() -> None:
    links = random_informants(np.random.default_rng(3), (40,), 12, 3)
    assert links.shape == (40, 12, 12)
    assert (links.sum(axis=-1) == 3).all()
    assert not links[:, np.arange(12), np.arange(12)].any()
    assert len({links[r].tobytes() for r in range(40)}) == 40


def test_arpso_inertia_grows_when_stuck_and_shrinks_when_improving() -> None:
    stuck = arpso_inertia(
        np.array([0.5]), np.array([0.5]), np.array([0.5]), np.array([0.5]), 1.0, 0.5, 0.4
    )
    improving = arpso_inertia(
        np.array([0.1]), np.array([0.8]), np.array([0.8]), np.array([0.1]), 1.0, 0.5, 0.4
    )
    assert stuck[0] == pytest.approx(1.4)
    assert improving[0] == pytest.approx(1.0 - 0.5 * (1 - 0.125) + 0.4 * 0.125)


@pytest.mark.parametrize("variant", ["pso", "spso", "arpso"])
def test_swarm_converges_on_a_signal(variant: str) -> None:
    """12 particles that all start inside the signal disc close in on the source."""
    rng = np.random.default_rng(2024)
    n = 12
    config = SwarmConfig(variant=variant, max_step=100.0)  # type: ignore[arg-type]
    angle = rng.uniform(0, 2 * np.pi, n)
    position = TARGET + 1900.0 * np.stack([np.cos(angle), np.sin(angle)], axis=1)
    step = np.zeros((n, 2))
    fit, src = _read(position)
    own = improve(Best(position.copy(), np.zeros(n), np.full(n, -1)), position, fit, src)
    everyone = ~np.eye(n, dtype=bool)
    start = np.linalg.norm(position - TARGET, axis=1).min()
    previous = own.fitness.copy()
    for _ in range(150):
        heard = Best(
            np.broadcast_to(own.position, (n, n, 2)),
            np.broadcast_to(own.fitness, (n, n)),
            np.broadcast_to(own.source, (n, n)),
        )
        social, mine = swarm_best(own, heard, everyone)
        w = arpso_inertia(previous, own.fitness, fit.max(), fit.mean(), 1.0, 0.5, 0.4)
        step = next_step(config, step, position, own, social, mine, np.full(n, w), rng)
        position = position + step
        fit, src = _read(position)
        previous = own.fitness.copy()
        own = improve(own, position, fit, src)
    closest = np.linalg.norm(own.position - TARGET, axis=1).min()
    assert start > 1800.0
    assert closest < 150.0


def test_lone_particle_without_signal_has_no_pull() -> None:
    """A particle with no best (fitness 0) is its own best: only inertia moves it."""
    rng = np.random.default_rng(5)
    config = SwarmConfig(variant="pso", max_step=1000.0, constant_speed=False)
    position = np.array([[100.0, 100.0]])
    nothing = Best(np.array([[9000.0, 9000.0]]), np.zeros(1), np.full(1, -1))
    step = np.array([[10.0, 0.0]])
    out = next_step(config, step, position, nothing, nothing, np.ones(1, bool), None, rng)
    assert np.allclose(out, config.inertia * step)
