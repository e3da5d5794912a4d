"""The tau-lag velocity loop (eq. 3-4), discretised exactly, and pursuit guidance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mdm_core.dynamics import LagModel, lag_step, pursuit_reference

TAU = 0.33


@pytest.mark.parametrize("t", [0.0, 0.01, 0.1, TAU, 1.0, 3.0, 10.0])
def test_one_step_from_rest_is_the_exact_step_response(t: float) -> None:
    q = np.array([[20.0, -5.0]])
    x, v = lag_step(np.zeros((1, 2)), np.zeros((1, 2)), q, t, LagModel(TAU))
    np.testing.assert_allclose(v, q * (1 - np.exp(-t / TAU)), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(x, q * (t - TAU * (1 - np.exp(-t / TAU))), rtol=1e-12, atol=1e-12)


def test_one_long_step_equals_many_short_steps() -> None:
    model = LagModel(TAU)
    rng = np.random.default_rng(0)
    x0 = rng.normal(0, 100, size=(5, 2))
    v0 = rng.normal(0, 10, size=(5, 2))
    q = rng.normal(0, 20, size=(5, 2))
    x1, v1 = lag_step(x0, v0, q, 10.0, model)
    x, v = x0, v0
    for _ in range(1000):
        x, v = lag_step(x, v, q, 0.01, model)
    np.testing.assert_allclose(x, x1, rtol=0, atol=1e-9)
    np.testing.assert_allclose(v, v1, rtol=0, atol=1e-9)


def test_velocity_error_decays_by_e_per_time_constant() -> None:
    _, v = lag_step(np.zeros(2), np.array([10.0, 0.0]), np.zeros(2), TAU, LagModel(TAU))
    np.testing.assert_allclose(v, [10.0 / math.e, 0.0], rtol=1e-14)


def test_zero_step_changes_nothing_and_inputs_are_not_modified() -> None:
    x0, v0, q = np.array([1.0, 2.0]), np.array([3.0, 4.0]), np.array([5.0, 6.0])
    x, v = lag_step(x0, v0, q, 0.0, LagModel(TAU))
    np.testing.assert_array_equal(x, [1.0, 2.0])
    np.testing.assert_array_equal(v, [3.0, 4.0])
    lag_step(x0, v0, q, 1.0, LagModel(TAU))
    np.testing.assert_array_equal(x0, [1.0, 2.0])
    np.testing.assert_array_equal(v0, [3.0, 4.0])


def test_negative_step_and_nonpositive_tau_are_rejected() -> None:
    with pytest.raises(ValueError, match="dt"):
        lag_step(np.zeros(2), np.zeros(2), np.zeros(2), -0.1, LagModel(TAU))
    with pytest.raises(ValueError, match="tau"):
        LagModel(0.0)


def test_pursuit_reference_points_at_the_waypoint_with_the_given_speed() -> None:
    pos = np.array([[0.0, 0.0], [100.0, 100.0]])
    wp = np.array([[30.0, 40.0], [100.0, 0.0]])
    q = pursuit_reference(pos, wp, 20.0)
    np.testing.assert_allclose(q, [[12.0, 16.0], [0.0, -20.0]], rtol=1e-14)


def test_pursuit_reference_is_zero_at_the_waypoint() -> None:
    q = pursuit_reference(np.array([[5.0, 5.0]]), np.array([[5.0, 5.0]]), 20.0)
    np.testing.assert_array_equal(q, [[0.0, 0.0]])


def test_pursuit_reference_slows_linearly_inside_the_slow_radius() -> None:
    pos = np.zeros((3, 2))
    wp = np.array([[0.0, 5.0], [0.0, 10.0], [0.0, 50.0]])
    q = pursuit_reference(pos, wp, 20.0, slow_radius=10.0)
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), [10.0, 20.0, 20.0], rtol=1e-14)


def test_pursuit_reference_takes_one_speed_per_vehicle() -> None:
    pos = np.zeros((2, 2))
    wp = np.array([[100.0, 0.0], [0.0, 100.0]])
    q = pursuit_reference(pos, wp, np.array([5.0, 15.0]))
    np.testing.assert_allclose(q, [[5.0, 0.0], [0.0, 15.0]], rtol=1e-14)
