"""The paper's first-order velocity loop (eq. 3-4), batched and discretised exactly.

    dX/dt = V,   dV/dt = (Q - V) / tau

With the reference Q held constant over a step of length dt the solution is closed-form, so any
step length gives the exact trajectory of the continuous model (no integration error).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class LagModel:
    """Velocity-loop parameters of one airframe."""

    tau: float = 0.33
    """Time constant of the closed velocity loop, seconds (paper: 0.33 s)."""

    def __post_init__(self) -> None:
        if not self.tau > 0:
            raise ValueError(f"LagModel.tau must be > 0 s, got {self.tau}")


def lag_step(
    position: FloatArray, velocity: FloatArray, reference: FloatArray, dt: float, model: LagModel
) -> tuple[FloatArray, FloatArray]:
    """Advance positions and velocities (..., d) by dt with the reference velocity held constant.

    Returns new (position, velocity); inputs are not modified.
    """
    if dt < 0:
        raise ValueError(f"dt must be >= 0, got {dt}")
    decay = np.exp(-dt / model.tau)
    error = velocity - reference
    new_velocity = reference + error * decay
    new_position = position + reference * dt + error * model.tau * (1.0 - decay)
    return new_position, new_velocity


def pursuit_reference(
    position: FloatArray, waypoint: FloatArray, speed: float | FloatArray, slow_radius: float = 0.0
) -> FloatArray:
    """Pursuit guidance: a velocity reference of the given speed pointing at the waypoint.

    Within ``slow_radius`` of the waypoint the speed falls linearly to zero so a vehicle
    settles on the point instead of orbiting it.
    """
    offset = waypoint - position
    distance = np.linalg.norm(offset, axis=-1, keepdims=True)
    speed_arr = np.asarray(speed, dtype=float)
    if speed_arr.ndim:
        speed_arr = speed_arr[..., None]
    if slow_radius > 0:
        speed_arr = speed_arr * np.minimum(1.0, distance / slow_radius)
    with np.errstate(invalid="ignore", divide="ignore"):
        direction = np.where(distance > 0, offset / np.where(distance > 0, distance, 1.0), 0.0)
    return np.asarray(direction * speed_arr, dtype=np.float64)
