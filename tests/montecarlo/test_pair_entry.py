"""The swarm engines' compiled pair entry times answer bit for bit as numpy's closed form."""

from __future__ import annotations

import numpy as np

from mdm_core.world import first_entry_time
from mdm_montecarlo.kernels.pair_entry import pair_entry_times

PAIRS = 5000
DT = 5.0
RADIUS = 400.0


def test_pair_entry_times_equal_first_entry_time_on_random_pairs() -> None:
    rng = np.random.default_rng(5)
    # Vehicles 0-600 m from their target: inside, crossing in the step, or out of reach.
    target = rng.uniform(0.0, 20000.0, (PAIRS, 2))
    gap = rng.uniform(0.0, 600.0, PAIRS)
    bearing = rng.uniform(0.0, 2 * np.pi, PAIRS)
    start = target + gap[:, None] * np.stack([np.cos(bearing), np.sin(bearing)], axis=1)
    heading = rng.uniform(0.0, 2 * np.pi, PAIRS)
    speed = rng.choice([0.0, 4.0, 20.0], PAIRS)
    velocity = speed[:, None] * np.stack([np.cos(heading), np.sin(heading)], axis=1)
    # Fixed targets and targets moving at up to 5 m/s; some pairs with equal velocities.
    target_velocity = rng.uniform(-5.0, 5.0, (PAIRS, 2)) * (rng.random((PAIRS, 1)) < 0.5)
    same = rng.random(PAIRS) < 0.05
    target_velocity[same] = velocity[same]
    # Targets present, appearing within the step, or after it.
    not_before = rng.choice([-100.0, 0.0, 2.5, 7.0], PAIRS)

    got = pair_entry_times(start, velocity, DT, target, target_velocity, RADIUS, not_before)
    expected = first_entry_time(
        start,
        velocity,
        np.full(PAIRS, DT),
        target[:, None, :],
        target_velocity[:, None, :],
        np.full(PAIRS, RADIUS),
        np.ones((PAIRS, 1), dtype=bool),
        not_before[:, None],
    )[:, 0]

    np.testing.assert_array_equal(got, expected)
    hits = np.isfinite(expected)
    # Enough contacts of each kind that a wrong kernel shows: already inside, entering later.
    assert (expected[hits] > 0).sum() > 200
    assert (expected[hits] == 0).sum() > 200
    assert (~hits).sum() > 200
