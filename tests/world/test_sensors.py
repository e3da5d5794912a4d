"""Detection and confirmation sensors (eqs. 5-6) and the exact time of first contact."""

from __future__ import annotations

import numpy as np
import pytest

from mdm_core.world.sensors import THRESHOLD, Sensor, contacts, first_entry_time


def _contacts_at(
    distance: float, radius: float, confirms: bool, false: bool = False, present: bool = True
) -> bool:
    mask, _ = contacts(
        radius=np.array([radius]),
        confirms=np.array([confirms]),
        vehicle=np.array([[1000.0, 1000.0]]),
        targets=np.array([[[1000.0 + distance, 1000.0]]]),
        present=np.array([[present]]),
        false_mask=np.array([false]),
    )
    return bool(mask[0, 0])


@pytest.mark.parametrize("radius", [2000.0, 400.0, 1.0])
@pytest.mark.parametrize("confirms", [False, True])
def test_target_exactly_at_the_radius_is_not_sensed(radius: float, confirms: bool) -> None:
    assert not _contacts_at(radius, radius, confirms)


@pytest.mark.parametrize("radius", [2000.0, 400.0, 1.0])
@pytest.mark.parametrize("confirms", [False, True])
def test_target_just_inside_the_radius_is_sensed(radius: float, confirms: bool) -> None:
    assert _contacts_at(radius - 1e-6, radius, confirms)


def test_false_target_fires_the_detection_sensor_but_never_confirmation() -> None:
    for d in (0.0, 100.0, 399.0):
        assert _contacts_at(d, 400.0, confirms=False, false=True)
        assert not _contacts_at(d, 400.0, confirms=True, false=True)


def test_target_not_yet_present_is_not_sensed() -> None:
    assert not _contacts_at(0.0, 400.0, confirms=False, present=False)
    assert not _contacts_at(0.0, 400.0, confirms=True, present=False)


def test_popup_target_is_sensed_from_its_appear_time_on() -> None:
    appear = np.array([200.0, 400.0])
    targets = np.array([[[0.0, 0.0], [10.0, 0.0]]])
    for t, expected in ((199.999, [False, False]), (200.0, [True, False]), (400.0, [True, True])):
        present = (appear <= t)[None, :]
        mask, _ = contacts(
            np.array([400.0]),
            np.array([True]),
            np.zeros((1, 2)),
            targets,
            present,
            np.zeros(2, dtype=bool),
        )
        assert mask[0].tolist() == expected


def test_each_vehicle_uses_its_own_active_sensor() -> None:
    vehicles = np.array([[0.0, 0.0], [0.0, 0.0]])
    targets = np.tile([[[1000.0, 0.0], [0.0, 100.0]]], (2, 1, 1))
    mask, strength = contacts(
        radius=np.array([2000.0, 400.0]),
        confirms=np.array([False, True]),
        vehicle=vehicles,
        targets=targets,
        present=np.ones((2, 2), dtype=bool),
        false_mask=np.array([False, True]),
    )
    assert mask.tolist() == [[True, True], [False, False]]
    np.testing.assert_allclose(strength[0], np.exp(-np.array([1000.0, 100.0]) / 2000.0))
    np.testing.assert_allclose(strength[1], np.exp(-np.array([1000.0, 100.0]) / 400.0))


def test_signal_strength_is_one_at_the_target_and_threshold_at_the_radius() -> None:
    sensor = Sensor(name="detection", radius=2000.0, confirms=False)
    np.testing.assert_allclose(sensor.strength(np.array([0.0, 2000.0])), [1.0, THRESHOLD])
    assert pytest.approx(np.exp(-1.0)) == THRESHOLD


def test_sensor_with_nonpositive_radius_is_rejected() -> None:
    with pytest.raises(ValueError, match="'confirmation': radius must be > 0 m"):
        Sensor(name="confirmation", radius=0.0, confirms=True)


def _entry(
    start: list[float],
    velocity: list[float],
    duration: float,
    target: list[float],
    radius: float,
    *,
    target_velocity: tuple[float, float] = (0.0, 0.0),
    eligible: bool = True,
    not_before: float = 0.0,
) -> float:
    t = first_entry_time(
        start=np.array([start]),
        velocity=np.array([velocity]),
        duration=np.array([duration]),
        target_start=np.array([[target]]),
        target_velocity=np.array([[target_velocity]]),
        radius=np.array([radius]),
        eligible=np.array([[eligible]]),
        not_before=np.array([[not_before]]),
    )
    return float(t[0, 0])


@pytest.mark.parametrize("offset", [0.0, 100.0, 399.0])
def test_straight_pass_enters_the_disc_at_the_analytic_chord_point(offset: float) -> None:
    r, speed, x0 = 400.0, 20.0, -3000.0
    t = _entry([x0, offset], [speed, 0.0], 1000.0, [0.0, 0.0], r)
    expected = (-x0 - np.sqrt(r**2 - offset**2)) / speed
    assert t == pytest.approx(expected, abs=1e-9)
    at = np.array([x0 + speed * t, offset])
    assert np.linalg.norm(at) == pytest.approx(r, abs=1e-9)


def test_entry_time_agrees_with_contacts_just_before_and_after() -> None:
    r, v = 400.0, np.array([12.0, 16.0])
    start = np.array([-2000.0, -2500.0])
    t = _entry(list(start), list(v), 500.0, [0.0, 0.0], r)
    for dt, expected in ((-1e-6, False), (1e-6, True)):
        mask, _ = contacts(
            np.array([r]),
            np.array([True]),
            (start + v * (t + dt))[None, :],
            np.zeros((1, 1, 2)),
            np.ones((1, 1), dtype=bool),
            np.zeros(1, dtype=bool),
        )
        assert bool(mask[0, 0]) is expected


def test_pass_that_misses_the_disc_gives_inf() -> None:
    assert _entry([-3000.0, 401.0], [20.0, 0.0], 1000.0, [0.0, 0.0], 400.0) == np.inf


def test_disc_reached_after_the_duration_gives_inf() -> None:
    # Entry would be at 130 s; the leg lasts 100 s.
    assert _entry([-3000.0, 0.0], [20.0, 0.0], 100.0, [0.0, 0.0], 400.0) == np.inf
    assert _entry([-3000.0, 0.0], [20.0, 0.0], 130.0, [0.0, 0.0], 400.0) == pytest.approx(130.0)


def test_ineligible_target_gives_inf() -> None:
    assert _entry([-3000.0, 0.0], [20.0, 0.0], 1000.0, [0.0, 0.0], 400.0, eligible=False) == np.inf


def test_vehicle_starting_inside_the_disc_enters_at_time_zero() -> None:
    assert _entry([100.0, 0.0], [20.0, 0.0], 10.0, [0.0, 0.0], 400.0) == 0.0


def test_popup_appearing_while_vehicle_is_inside_is_sensed_at_the_appear_time() -> None:
    # The vehicle is inside the disc from 130 s to 170 s; the target appears at 150 s.
    t = _entry([-3000.0, 0.0], [20.0, 0.0], 1000.0, [0.0, 0.0], 400.0, not_before=150.0)
    assert t == 150.0


def test_popup_appearing_after_the_vehicle_left_the_disc_gives_inf() -> None:
    t = _entry([-3000.0, 0.0], [20.0, 0.0], 1000.0, [0.0, 0.0], 400.0, not_before=170.5)
    assert t == np.inf


def test_popup_appearing_before_the_pass_is_sensed_at_the_crossing() -> None:
    t = _entry([-3000.0, 0.0], [20.0, 0.0], 1000.0, [0.0, 0.0], 400.0, not_before=50.0)
    assert t == pytest.approx(130.0, abs=1e-9)


def test_target_moving_towards_a_hovering_vehicle_is_met_at_relative_distance() -> None:
    t = _entry([0.0, 0.0], [0.0, 0.0], 1000.0, [1000.0, 0.0], 400.0, target_velocity=(-5.0, 0.0))
    assert t == pytest.approx(120.0, abs=1e-9)


def test_hovering_vehicle_and_fixed_target_meet_only_if_already_inside() -> None:
    assert _entry([0.0, 0.0], [0.0, 0.0], 100.0, [300.0, 0.0], 400.0, not_before=7.0) == 7.0
    assert _entry([0.0, 0.0], [0.0, 0.0], 100.0, [500.0, 0.0], 400.0) == np.inf


def test_entry_times_are_batched_over_vehicles_and_targets() -> None:
    t = first_entry_time(
        start=np.array([[-3000.0, 0.0], [0.0, -3000.0]]),
        velocity=np.array([[20.0, 0.0], [0.0, 10.0]]),
        duration=np.array([1000.0, 1000.0]),
        target_start=np.zeros((2, 2, 2)) + np.array([[[0.0, 0.0]], [[0.0, 0.0]]]),
        target_velocity=np.zeros((2, 2, 2)),
        radius=np.array([400.0, 2000.0]),
        eligible=np.array([[True, False], [True, True]]),
        not_before=np.zeros((2, 2)),
    )
    np.testing.assert_allclose(t, [[130.0, np.inf], [100.0, 100.0]], rtol=1e-12)
