"""Batched gathers of mdm_core.search.pso against plain per-particle loops."""

from __future__ import annotations

import numpy as np

from mdm_core.search.pso import Best, forget, random_informants, swarm_best


def _random_best(rng: np.random.Generator, shape: tuple[int, ...], targets: int) -> Best:
    source = np.where(rng.random(shape) < 0.5, -1, rng.integers(0, targets, shape))
    fitness = np.where(source >= 0, rng.random(shape), 0.0)
    return Best(rng.random((*shape, 2)), fitness, source.astype(np.intp))


def test_swarm_best_matches_a_loop_over_particles() -> None:
    rng = np.random.default_rng(5)
    own = _random_best(rng, (4, 6), 3)
    heard = _random_best(rng, (4, 6, 6), 3)
    links = rng.random((4, 6, 6)) < 0.5
    links[0, 0] = False  # a particle that listens to nobody
    best, mine = swarm_best(own, heard, links)
    for r in range(4):
        for i in range(6):
            candidates = np.where(links[r, i], heard.fitness[r, i], -np.inf)
            j = int(np.argmax(candidates))
            assert mine[r, i] == (own.fitness[r, i] >= candidates[j])
            if mine[r, i]:
                expected = (own.position[r, i], own.fitness[r, i], own.source[r, i])
            else:
                expected = (heard.position[r, i, j], candidates[j], heard.source[r, i, j])
            assert best.position[r, i].tolist() == expected[0].tolist()
            assert best.fitness[r, i] == expected[1]
            assert best.source[r, i] == expected[2]


def test_forget_reads_a_broadcast_known_table() -> None:
    """The live companion hands one known row per vehicle, broadcast over the heard slots."""
    rng = np.random.default_rng(6)
    heard = _random_best(rng, (1, 5), 4)
    known = np.array([[True, False, True, False]])
    out = forget(heard, np.broadcast_to(known[:, None, :], (1, 5, 4)))
    stale = (heard.source >= 0) & known[0, np.maximum(heard.source, 0)]
    assert out.fitness.tolist() == np.where(stale, 0.0, heard.fitness).tolist()
    assert out.source.tolist() == np.where(stale, -1, heard.source).tolist()


def test_random_informants_all_others_or_none() -> None:
    everyone = random_informants(np.random.default_rng(1), (3,), 5, 9)
    assert (everyone == ~np.eye(5, dtype=bool)).all()
    alone = random_informants(np.random.default_rng(1), (), 1, 3)
    assert alone.shape == (1, 1)
    assert not alone.any()
