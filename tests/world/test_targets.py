"""Targets: fixed, pop-up and the paper's random walk (eq. 2), batched over runs."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from mdm_core.world.area import Area
from mdm_core.world.targets import RandomWalk, TargetSpec, TargetTracks, WalkBoundary

BIG = Area(1e7, 1e7)


def spec(*positions: tuple[float, float]) -> TargetSpec:
    m = len(positions)
    return TargetSpec(
        positions=np.array(positions, dtype=float),
        appear_times=np.zeros(m),
        false_mask=np.zeros(m, dtype=bool),
    )


def test_target_spec_counts_real_targets() -> None:
    s = TargetSpec(
        positions=np.zeros((3, 2)),
        appear_times=np.array([0.0, 200.0, 400.0]),
        false_mask=np.array([False, True, False]),
    )
    assert (s.count, s.real_count) == (3, 2)


def test_target_spec_with_mismatched_shapes_is_rejected() -> None:
    with pytest.raises(ValueError, match="shape"):
        TargetSpec(np.zeros((3, 3)), np.zeros(3), np.zeros(3, dtype=bool))
    with pytest.raises(ValueError, match="one entry per target"):
        TargetSpec(np.zeros((3, 2)), np.zeros(2), np.zeros(3, dtype=bool))


def test_fixed_targets_never_move() -> None:
    tracks = TargetTracks(spec((1.0, 2.0), (3.0, 4.0)), Area(10, 10), 3, np.random.default_rng(0))
    run, t = np.array([0, 2]), np.array([0.0, 1e6])
    np.testing.assert_array_equal(tracks.positions(run, t), [[[1, 2], [3, 4]]] * 2)
    np.testing.assert_array_equal(tracks.motion(run, t)[1], np.zeros((2, 2, 2)))
    assert np.all(np.isinf(tracks.next_node_time(t)))
    assert not tracks.moving


def _displacement(walk: RandomWalk, grid_dt: float, t: float, runs: int, seed: int) -> np.ndarray:
    tracks = TargetTracks(spec((5e6, 5e6)), BIG, runs, np.random.default_rng(seed), walk, grid_dt)
    pos = tracks.positions(np.arange(runs), np.full(runs, t))
    return np.asarray(pos[:, 0, :] - 5e6)


@pytest.mark.parametrize(("grid_dt", "t"), [(0.1, 20.0), (10.0, 200.0)])
def test_paper_walk_drifts_two_metres_per_second_per_axis(grid_dt: float, t: float) -> None:
    walk = RandomWalk(speed=5.0, low=-0.2, high=1.0, sample_time=0.1, boundary="free")
    d = _displacement(walk, grid_dt, t, 2000, seed=1)
    mean, std = walk.step_moments(round(t / 0.1))
    assert mean == pytest.approx(2.0 * t)
    # Standard error of the mean over 2000 runs is std / 45; allow about 5 of them.
    np.testing.assert_allclose(d.mean(axis=0), [2.0 * t, 2.0 * t], atol=5 * std / np.sqrt(2000))
    np.testing.assert_allclose(d.std(axis=0), [std, std], rtol=0.06)


def test_walk_on_the_sample_time_grid_takes_exact_uniform_steps() -> None:
    walk = RandomWalk(speed=5.0, low=-0.2, high=1.0, sample_time=0.1, boundary="free")
    tracks = TargetTracks(spec((5e6, 5e6)), BIG, 50, np.random.default_rng(2), walk, 0.1)
    times = np.arange(0, 101) * 0.1
    pos = np.stack([tracks.positions(np.arange(50), np.full(50, t)) for t in times])
    steps = np.diff(pos, axis=0).ravel()
    assert steps.min() >= -0.1 - 1e-9
    assert steps.max() <= 0.5 + 1e-9
    assert stats.kstest(steps, stats.uniform(-0.1, 0.6).cdf).statistic < 1.63 / np.sqrt(steps.size)


def test_shared_axes_walk_moves_both_axes_alike() -> None:
    walk = RandomWalk(shared_axes=True, boundary="free")
    d = _displacement(walk, 0.1, 5.0, 20, seed=3)
    np.testing.assert_allclose(d[:, 0], d[:, 1], atol=1e-6)
    assert np.ptp(d[:, 0]) > 0


@pytest.mark.parametrize("boundary", ["reflect", "clamp", "bounce"])
@pytest.mark.parametrize("grid_dt", [0.1, 10.0])
def test_bounded_walks_keep_targets_inside_the_area(boundary: WalkBoundary, grid_dt: float) -> None:
    area = Area(300.0, 200.0)
    walk = RandomWalk(speed=5.0, low=-0.2, high=1.0, sample_time=0.1, boundary=boundary)
    s = spec((1.0, 1.0), (299.0, 199.0), (150.0, 100.0))
    tracks = TargetTracks(s, area, 20, np.random.default_rng(4), walk, grid_dt)
    horizon = 200 * grid_dt
    for t in np.linspace(0.0, horizon, 97):
        pos = tracks.positions(np.arange(20), np.full(20, t))
        assert np.all(area.contains(pos, margin=1e-9))


def test_free_walk_may_leave_the_area() -> None:
    area = Area(100.0, 100.0)
    walk = RandomWalk(boundary="free")
    tracks = TargetTracks(spec((90.0, 90.0)), area, 5, np.random.default_rng(5), walk, 10.0)
    assert not np.any(area.contains(tracks.positions(np.arange(5), np.full(5, 100.0))))


def test_positions_are_linear_between_grid_nodes() -> None:
    walk = RandomWalk(boundary="free")
    tracks = TargetTracks(spec((5e6, 5e6)), BIG, 2, np.random.default_rng(6), walk, 10.0)
    run = np.arange(2)
    a = tracks.positions(run, np.full(2, 30.0))
    b = tracks.positions(run, np.full(2, 40.0))
    mid = tracks.positions(run, np.full(2, 32.5))
    np.testing.assert_allclose(mid, a + 0.25 * (b - a), rtol=1e-12)
    np.testing.assert_allclose(tracks.motion(run, np.full(2, 32.5))[1], (b - a) / 10.0)
    np.testing.assert_allclose(tracks.next_node_time(np.array([30.0, 32.5])), [40.0, 40.0])


def test_track_does_not_depend_on_the_order_of_queries() -> None:
    walk = RandomWalk()
    area = Area(20000.0, 20000.0)
    s = spec((1000.0, 1000.0), (10000.0, 5000.0))
    late_first = TargetTracks(s, area, 3, np.random.default_rng(7), walk, 10.0)
    in_order = TargetTracks(s, area, 3, np.random.default_rng(7), walk, 10.0)
    run = np.arange(3)
    final = late_first.positions(run, np.full(3, 7000.0))
    for t in np.arange(0.0, 7001.0, 500.0):
        in_order.positions(run, np.full(3, t))
    np.testing.assert_array_equal(in_order.positions(run, np.full(3, 7000.0)), final)


def test_grid_that_is_not_a_multiple_of_the_sample_time_is_rejected() -> None:
    with pytest.raises(ValueError, match="whole multiple"):
        TargetTracks(spec((1, 1)), BIG, 1, np.random.default_rng(0), RandomWalk(), 0.25)


@pytest.mark.parametrize("boundary", ["reflect", "bounce"])
@pytest.mark.parametrize("horizon", [5000.0, 20000.0])
def test_room_reserved_for_a_horizon_changes_no_draw(
    boundary: WalkBoundary, horizon: float
) -> None:
    """A track with room reserved up front draws the same path as one whose buffers double,
    before, at and past the horizon."""
    walk = RandomWalk(boundary=boundary)
    area = Area(20000.0, 20000.0)
    s = spec((1000.0, 1000.0), (19990.0, 5000.0), (10000.0, 10.0))
    grown = TargetTracks(s, area, 4, np.random.default_rng(8), walk, 50.0)
    reserved = TargetTracks(s, area, 4, np.random.default_rng(8), walk, 50.0, horizon=horizon)
    for until in (100.0, 4999.0, 5000.0, 12000.0, 30000.0):
        a, b = grown.segments(until), reserved.segments(until)
        k = int(until // 50.0)
        np.testing.assert_array_equal(a[0][:, : k + 1], b[0][:, : k + 1])
        np.testing.assert_array_equal(a[1][:, : k + 1], b[1][:, : k + 1])
        assert grown.max_speed == reserved.max_speed
    run = np.arange(4)
    t = np.array([0.0, 4999.9, 5000.0, 29999.0])
    np.testing.assert_array_equal(grown.positions(run, t), reserved.positions(run, t))


def test_departure_is_the_first_time_the_path_leaves_the_area() -> None:
    """tracks.departures: exact first exit from the area on the linear segments, checked
    against the path sampled every 0.05 s (inside just before, outside just after)."""
    area = Area(2000.0, 1500.0)
    walk = RandomWalk(speed=20.0, boundary="free")  # drifts 8 m/s per axis, noise 3 m/step
    points = spec((1000.0, 700.0), (1900.0, 100.0), (300.0, 1400.0))
    tracks = TargetTracks(points, area, 4, np.random.default_rng(3), walk, 25.0)
    gone = tracks.departures(1000.0)
    assert np.isfinite(gone).all()
    runs = np.arange(4)
    for j in range(points.count):
        for run in runs:
            t = gone[run, j]
            before = np.arange(0.0, t - 1e-6, 0.05)
            inside = area.contains(tracks.positions(np.full(len(before), run), before)[:, j])
            assert inside.all()
            after = tracks.positions(np.array([run]), np.array([t + 1e-3]))[0, j]
            assert not area.contains(after)
    # a later horizon finds the same times; a shorter one none past it
    np.testing.assert_array_equal(tracks.departures(4000.0), gone)
    short = tracks.departures(float(gone.min()))
    assert np.isinf(short[gone > gone.min()]).all()


@pytest.mark.parametrize("boundary", ["reflect", "clamp", "bounce"])
def test_bounded_and_fixed_targets_never_depart(boundary: WalkBoundary) -> None:
    """A clamped target reaches the wall within 10 s here and stays on it: it is not gone."""
    area = Area(100.0, 100.0)
    walk = RandomWalk(boundary=boundary)
    bounded = TargetTracks(spec((90.0, 90.0)), area, 5, np.random.default_rng(5), walk, 10.0)
    fixed = TargetTracks(spec((90.0, 90.0)), area, 5, np.random.default_rng(5))
    assert np.isinf(bounded.departures(2000.0)).all()
    assert np.isinf(fixed.departures(2000.0)).all()
