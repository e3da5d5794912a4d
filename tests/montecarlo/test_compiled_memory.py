"""The engine's compiled memory check answers bit for bit as the numpy policy's."""

from __future__ import annotations

import numpy as np

from mdm_core.search import SearchPolicy
from mdm_core.search.from_profile import policy_config
from mdm_montecarlo.kernels.compiled_memory import CompiledMemoryPolicy
from mdm_profiles import builtin_profile

LANES = 500
TARGETS = 10


def test_memory_distances_equal_the_numpy_policy() -> None:
    config = policy_config(builtin_profile("paper-fixed"))
    numpy_policy, compiled = SearchPolicy(config), CompiledMemoryPolicy(config)
    rng = np.random.default_rng(5)
    state = numpy_policy.start(rng.uniform(0, 20000, (LANES, 2)), np.zeros(LANES), rng)
    # Lanes remember 0 to 9 confirmed positions (the buffer grows past its first 4 slots).
    per_lane = rng.integers(0, 10, LANES)
    owners = np.repeat(np.arange(LANES), per_lane)
    numpy_policy.remember(state, owners, rng.uniform(0, 20000, (owners.size, 2)))
    lanes = rng.permutation(LANES)[: LANES // 2]
    positions = rng.uniform(0, 20000, (lanes.size, TARGETS, 2))
    positions[3, 4] = np.nan

    got = compiled.memory_distance2(state, lanes, positions)
    np.testing.assert_array_equal(got, numpy_policy.memory_distance2(state, lanes, positions))
    assert np.isinf(got[per_lane[lanes] == 0]).all()
    assert np.isfinite(got[per_lane[lanes] > 0]).sum() > lanes.size
    # One position per lane as a view (the vehicle's own position, as ignores_detections asks).
    own = positions[:, 0, :][:, None, :]
    np.testing.assert_array_equal(
        compiled.memory_distance2(state, lanes, own),
        numpy_policy.memory_distance2(state, lanes, own),
    )
