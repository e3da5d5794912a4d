"""The rectangular search area, its walls and its perimeter; the scenario built on it."""

from __future__ import annotations

import numpy as np
import pytest

from mdm_core.world.area import Area
from mdm_core.world.scenario import Scenario
from mdm_profiles import builtin_profile


def test_area_with_nonpositive_extent_is_rejected() -> None:
    with pytest.raises(ValueError, match="> 0 m"):
        Area(0.0, 10.0)


def test_contains_includes_the_walls_and_honours_the_margin() -> None:
    area = Area(100.0, 50.0)
    pts = np.array([[0.0, 0.0], [100.0, 50.0], [100.1, 10.0], [-0.1, 10.0], [10.0, 50.5]])
    assert area.contains(pts).tolist() == [True, True, False, False, False]
    assert area.contains(pts, margin=1.0).tolist() == [True] * 5


def test_reflect_mirrors_points_at_the_walls() -> None:
    area = Area(100.0, 50.0)
    pts = np.array([[-10.0, 20.0], [110.0, 60.0], [250.0, -120.0], [30.0, 40.0]])
    np.testing.assert_allclose(
        area.fold(pts, "reflect"), [[10.0, 20.0], [90.0, 40.0], [50.0, 20.0], [30.0, 40.0]]
    )


def test_clip_moves_points_onto_the_nearest_wall() -> None:
    area = Area(100.0, 50.0)
    pts = np.array([[-10.0, 20.0], [110.0, 60.0]])
    np.testing.assert_array_equal(area.fold(pts, "clip"), [[0.0, 20.0], [100.0, 50.0]])


def test_perimeter_walk_starts_at_the_origin_and_visits_the_corners() -> None:
    area = Area(100.0, 50.0)
    # Perimeter 300 m: east 50, north 100, back 50, down 100.
    s = np.array([0.0, 50.0, 150.0, 200.0, 1.0]) / np.array([300.0, 300.0, 300.0, 300.0, 1.0])
    np.testing.assert_allclose(
        area.perimeter_point(s), [[0, 0], [0, 50], [100, 50], [100, 0], [0, 0]], atol=1e-12
    )


def test_perimeter_points_lie_on_the_boundary_at_the_right_arc_length() -> None:
    area = Area(100.0, 50.0)
    s = np.linspace(0.0, 1.0, 3001)
    p = area.perimeter_point(s)
    on_wall = np.isclose(p[:, 0], 0) | np.isclose(p[:, 0], 100) | np.isclose(p[:, 1], 0)
    on_wall |= np.isclose(p[:, 1], 50)
    assert np.all(on_wall)
    assert np.all(area.contains(p, margin=1e-9))
    # Consecutive points are 0.1 m apart along the boundary (shorter only across a corner).
    gaps = np.linalg.norm(np.diff(p, axis=0), axis=1)
    assert np.all(gaps <= 0.1 + 1e-9)
    assert np.mean(np.isclose(gaps, 0.1)) > 0.99


def test_scenario_of_popup_false_profile_has_appear_times_and_false_targets() -> None:
    scenario = Scenario.from_profile(builtin_profile("paper-popup-false"))
    np.testing.assert_array_equal(scenario.targets.appear_times, 200.0 * np.arange(1, 11))
    assert np.flatnonzero(scenario.targets.false_mask).tolist() == [2, 5, 8]
    assert [s.confirms for s in scenario.sensors] == [False, True]
    assert scenario.confirmation.radius == 400.0
    assert scenario.walk is None


def test_scenario_of_dynamic_profile_has_the_paper_walk() -> None:
    scenario = Scenario.from_profile(builtin_profile("paper-dynamic"))
    assert scenario.walk is not None
    assert scenario.walk.step_moments(10)[0] == pytest.approx(2.0)
    tracks = scenario.tracks(4, np.random.default_rng(0))
    assert tracks.moving


@pytest.mark.parametrize("placement", ["periphery_random", "periphery_even"])
def test_start_positions_lie_on_the_periphery(placement: str) -> None:
    scenario = Scenario.from_profile(builtin_profile("paper-fixed"))
    start = scenario.start_positions(50, 12, placement, np.random.default_rng(1))
    assert start.shape == (50, 12, 2)
    on_wall = np.isclose(start, 0.0).any(axis=-1) | np.isclose(start, 20000.0).any(axis=-1)
    assert np.all(on_wall)
