"""The kinematic state of every vehicle, stepped together with the shared tau-lag dynamics.

Horizontal motion is the paper's loop (``dynamics.lag_step``) with the reference either a
commanded velocity or pursuit of a target point. Pursuit slows within ``4 tau v`` of the point,
which makes the closed loop ``tau s^2 + s + k`` with ``k = 1 / (4 tau)`` critically damped, so a
vehicle settles on a position setpoint without overshoot. Vertical motion uses the same lag.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mdm_core.dynamics import LagModel
from sim_vehicle_stub.fleet_step_kernel import GROUND_ALT, load_step, step_fleet
from sim_vehicle_stub.tilt_kernel import tilt_tangents

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


class Fleet:
    """Arrays of all vehicles' state; index i is vehicle i. Altitude is metres above home, up."""

    def __init__(self, start: FloatArray, model: LagModel, speed: float) -> None:
        n = len(start)
        load_step()
        self.model = model
        # Position and altitude (velocity and climb rate) live in one (n, 3) array, so one lag
        # step moves all three axes; pos/alt (vel/vz) are views of it, updated in place.
        self._where = np.zeros((n, 3))
        self._speed = np.zeros((n, 3))
        self._ref = np.zeros((n, 3))
        self.pos: FloatArray = self._where[:, :2]
        self.pos[:] = np.array(start, dtype=float).reshape(n, 2)
        self.alt: FloatArray = self._where[:, 2]
        self.vel: FloatArray = self._speed[:, :2]
        self.vz: FloatArray = self._speed[:, 2]
        self._decay: dict[float, float] = {}
        self.yaw = np.zeros(n)
        self.h_ref: FloatArray = self._ref[:, :2]
        """Last horizontal velocity reference, for attitude."""
        self.h_use_vel = np.zeros(n, dtype=bool)
        self.h_target = self.pos.copy()
        self._cmd_vel = np.zeros((n, 3))
        self._acc = np.zeros((n, 3))
        self.h_vel: FloatArray = self._cmd_vel[:, :2]
        self.v_use_vel = np.zeros(n, dtype=bool)
        self.v_target = np.zeros(n)
        self.v_vel: FloatArray = self._cmd_vel[:, 2]
        self.speed = np.full(n, float(speed))
        self.climb = np.full(n, 3.0)
        self.descent = np.full(n, 1.5)
        self.yaw_cmd = np.full(n, np.nan)
        self.yaw_rate = np.full(n, np.nan)
        """Commanded yaw rate, rad/s (NaN: none)."""
        self.h_acc: FloatArray = self._acc[:, :2]
        self.v_acc: FloatArray = self._acc[:, 2]
        """Acceleration-only targets, integrated into the commanded velocities."""
        self.attitude()  # its kernel compiled or loaded now, not in the first tick of a loop

    def __len__(self) -> int:
        return len(self.pos)

    def on_ground(self) -> BoolArray:
        return np.asarray((self.alt <= GROUND_ALT) & (self.vz <= 0.05))

    # Commands for one vehicle; the step applies them to all at once.
    def hold(self, i: int) -> None:
        """Stop and hold the current position and altitude."""
        self.h_use_vel[i] = False
        self.h_target[i] = self.pos[i]
        self.h_acc[i] = 0.0
        self.v_acc[i] = 0.0
        self.v_use_vel[i] = False
        self.v_target[i] = self.alt[i]

    def go_to(self, i: int, north: float, east: float) -> None:
        self.h_acc[i] = 0.0
        self.h_use_vel[i] = False
        self.h_target[i] = (north, east)

    def fly_velocity(self, i: int, vn: float, ve: float) -> None:
        self.h_use_vel[i] = True
        self.h_vel[i] = (vn, ve)

    def climb_to(self, i: int, alt: float) -> None:
        self.v_acc[i] = 0.0
        self.v_use_vel[i] = False
        self.v_target[i] = alt

    def climb_rate(self, i: int, rate: float) -> None:
        """Vertical speed, m/s up."""
        self.v_use_vel[i] = True
        self.v_vel[i] = rate

    def step(self, dt: float) -> None:
        """Advance every vehicle by dt sim seconds: ``pursuit_reference`` and ``lag_step``
        operation for operation (the same results to the bit), compiled (this runs twice per
        telemetry tick for the whole fleet)."""
        tau = self.model.tau
        decay = self._decay.get(dt)
        if decay is None:
            if dt < 0:
                raise ValueError(f"dt must be >= 0, got {dt}")
            decay = self._decay[dt] = float(np.exp(-dt / tau))
        self._cmd_vel += self._acc * dt  # h_vel += h_acc dt, v_vel += v_acc dt
        offset = self.h_target - self.pos
        dist = np.hypot(offset[:, 0], offset[:, 1])
        norm = np.hypot(self.h_vel[:, 0], self.h_vel[:, 1])
        step_fleet(
            self._where, self._speed, self._ref, self._cmd_vel, self.h_target, dist, norm,
            self.h_use_vel, self.v_use_vel, self.v_target, self.speed, self.climb, self.descent,
            tau, dt, decay,
        )  # fmt: skip

    def update_yaw(self, dt: float) -> None:
        """Heading after ``dt`` s: the commanded yaw, else turning at the commanded yaw rate,
        else the direction of travel (kept when hovering)."""
        moving = np.hypot(self.vel[:, 0], self.vel[:, 1]) > 0.5
        heading = np.arctan2(self.vel[:, 1], self.vel[:, 0])
        course = np.where(moving, heading, self.yaw)
        turned = np.remainder(self.yaw + self.yaw_rate * dt, 2 * np.pi)
        turning = np.where(np.isnan(self.yaw_rate), course, turned)
        commanded = ~np.isnan(self.yaw_cmd)
        self.yaw = np.where(commanded, self.yaw_cmd, turning)

    def attitude(self, g: float = 9.81) -> tuple[FloatArray, FloatArray]:
        """Roll and pitch (rad) that produce the current lag-loop acceleration."""
        c, s = np.cos(self.yaw), np.sin(self.yaw)
        right, forward = tilt_tangents(self._ref, self._speed, c, s, self.model.tau, g)
        return np.arctan(right), -np.arctan(forward)
