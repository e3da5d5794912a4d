"""The engine's cache of remembered targets answers as SearchPolicy.known at every event, while
dynamic targets cross the memory circle and lanes confirm new targets."""

from __future__ import annotations

import numpy as np
import pytest

from mdm_core.search import SearchPolicy
from mdm_core.search.from_profile import policy_config
from mdm_core.world import Scenario
from mdm_montecarlo.kernels.compiled_tracks import compiled_tracks
from mdm_montecarlo.kernels.remembered import RememberedTargets
from mdm_profiles import builtin_profile

RUNS, VEHICLES = 30, 4


@pytest.mark.parametrize("scenario", ["paper-dynamic", "paper-fixed"])
def test_cached_answers_are_the_exact_ones(scenario: str) -> None:
    profile = builtin_profile(scenario)
    policy = SearchPolicy(policy_config(profile))
    radius = policy.config.memory_radius
    tracks = compiled_tracks(Scenario.from_profile(profile), RUNS, np.random.default_rng(1), 9000.0)
    rng = np.random.default_rng(2)
    n = RUNS * VEHICLES
    run_of = np.repeat(np.arange(RUNS), VEHICLES)
    state = policy.start(rng.uniform(0, 20000, (n, 2)), np.zeros(n), rng)
    cache = RememberedTargets(radius, tracks, n, tracks.spec.count)
    time = np.zeros(n)
    flips = 0
    previous = np.zeros((n, tracks.spec.count), dtype=bool)
    for _ in range(300):
        lanes = np.sort(rng.choice(n, n // 2, replace=False))
        time[lanes] += rng.exponential(30.0, lanes.size)
        t, runs = time[lanes], run_of[lanes]
        exact = rng.random(lanes.size) < 0.7
        got = cache.eligible(state, lanes, runs, t, exact)
        target = tracks.positions(runs, t)
        want = np.ones_like(got)
        known = policy.known(state, lanes, target)
        want[exact] = ~known[exact]
        np.testing.assert_array_equal(got, want)
        flips += int((known[exact] != previous[lanes][exact]).sum())
        previous[lanes[exact]] = known[exact]
        # Some lanes confirm a target: remembered a little off its position at their time.
        confirming = rng.random(lanes.size) < 0.05
        which = rng.integers(0, tracks.spec.count, confirming.sum())
        spot = target[confirming, which] + rng.normal(0, radius / 2, (which.size, 2))
        policy.remember(state, lanes[confirming], spot)
        cache.forget(lanes[confirming])
    assert flips > 50
