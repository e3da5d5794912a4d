"""The engine's cache of remembered targets answers exactly as the policy's memory check."""

from __future__ import annotations

import numpy as np

from mdm_core.search import SearchPolicy
from mdm_core.search.from_profile import policy_config
from mdm_core.world import Scenario
from mdm_montecarlo.remembered import RememberedTargets
from mdm_profiles import builtin_profile

RUNS = 40


def test_cached_answer_equals_the_policy_memory_check_as_targets_drift() -> None:
    profile = builtin_profile("paper-dynamic")
    scenario = Scenario.from_profile(profile)
    policy = SearchPolicy(policy_config(profile))
    rng = np.random.default_rng(7)
    tracks = scenario.tracks(RUNS, rng)
    lanes = np.arange(RUNS)
    state = policy.start(np.zeros((RUNS, 2)), np.zeros(RUNS), rng)
    cache = RememberedTargets(policy, tracks, RUNS, scenario.targets.count)
    changes = 0
    previous = None
    for t in np.arange(0.0, 3000.0, 37.0):
        now = np.full(RUNS, t)
        positions = tracks.positions(lanes, now)
        if t in (0.0, 370.0, 1110.0):
            # Each lane confirms the target it is assigned, where that target is now.
            target = (lanes + int(t)) % scenario.targets.count
            policy.remember(state, lanes, positions[lanes, target])
            cache.forget(lanes)
        expected = policy.known(state, lanes, positions)
        got = cache.known(state, lanes, lanes, now)
        np.testing.assert_array_equal(got, expected)
        if previous is not None:
            changes += int((expected != previous).sum())
        previous = expected
    # The targets drift out of the 400 m memory disc: the answer must have changed on its own.
    assert changes > RUNS
