"""The engines' compiled track growth draws the paths of TargetTracks bit for bit, for every
boundary rule, with shared or separate axes, on and off the walk's sampling grid."""

from __future__ import annotations

import numpy as np
import pytest

from mdm_core.world.area import Area
from mdm_core.world.targets import RandomWalk, TargetSpec, TargetTracks, WalkBoundary
from mdm_montecarlo.kernels.compiled_tracks import CompiledTracks

RUNS = 25
SPEC = TargetSpec(
    positions=np.array([[100.0, 100.0], [2900.0, 50.0], [1500.0, 1990.0], [0.0, 2000.0]]),
    appear_times=np.zeros(4),
    false_mask=np.zeros(4, dtype=bool),
)
AREA = Area(3000.0, 2000.0)  # small: the targets meet the walls many times


@pytest.mark.parametrize("boundary", ["reflect", "clamp", "bounce", "free"])
@pytest.mark.parametrize("shared_axes", [False, True])
@pytest.mark.parametrize("grid_dt", [0.1, 50.0])
def test_compiled_growth_draws_the_numpy_paths(
    boundary: WalkBoundary, shared_axes: bool, grid_dt: float
) -> None:
    walk = RandomWalk(speed=8.0, shared_axes=shared_axes, boundary=boundary)
    a = TargetTracks(SPEC, AREA, RUNS, np.random.default_rng(4), walk, grid_dt)
    b = CompiledTracks(SPEC, AREA, RUNS, np.random.default_rng(4), walk, grid_dt, horizon=10.0)
    until = 200 * grid_dt  # seven chunks: past the reserved room, so b's buffers grow too
    start_a, velocity_a = a.segments(until)
    start_b, velocity_b = b.segments(until)
    k = int(until / grid_dt) + 1
    np.testing.assert_array_equal(start_b[:, :k], start_a[:, :k])
    np.testing.assert_array_equal(velocity_b[:, :k], velocity_a[:, :k])
    assert b.max_speed == a.max_speed > 0
    run = np.arange(RUNS)
    t = np.linspace(0.0, until, RUNS)
    np.testing.assert_array_equal(b.positions(run, t), a.positions(run, t))
    # The same place in the random stream afterwards.
    assert a.rng.random() == b.rng.random()
    if boundary != "free":
        assert AREA.contains(a.positions(run, t).reshape(-1, 2)).all()
