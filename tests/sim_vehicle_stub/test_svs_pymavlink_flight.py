"""pymavlink flies the PX4 persona through OFFBOARD and the ArduPilot persona through GUIDED over
real UDP; the response to a velocity step is the tau-lag model and position setpoints settle."""

from __future__ import annotations

import logging
import math
from typing import Any

import pytest

from tests.emulator_harness import (
    TAU,
    Client,
    fitted_tau,
    free_udp_base,
    make_config,
    running_emulator,
    step_samples,
)

log = logging.getLogger(__name__)
PX4_HOLD, PX4_OFFBOARD = 0x3040000, 0x60000
TAU_TOLERANCE = 0.02
"""Seconds: |fitted tau - profile tau| allowed for a velocity step seen through MAVLink."""
SETTLE_TOLERANCE = 1.0
"""Metres: distance to a position setpoint after settling."""
OVERSHOOT_TOLERANCE = 0.5
"""Metres: how far past a position setpoint the vehicle may go."""


def _is_local(m: Any) -> bool:
    return bool(m.get_type() == "LOCAL_POSITION_NED")


def _check_velocity_step(c: Client, vn: float, ve: float) -> None:
    c.log.clear()
    reached = c.stream_until(
        lambda: c.velocity(vn, ve),
        lambda m: _is_local(m) and abs(m.vx - vn) < 0.02 and abs(m.vy - ve) < 0.02,
        15.0,
    )
    assert reached is not None
    c.stream(lambda: c.velocity(vn, ve), 0.2)
    last = c.log[-1]
    assert last.vx == pytest.approx(vn, abs=0.05)
    assert last.vy == pytest.approx(ve, abs=0.05)
    for axis, target in (("vx", vn), ("vy", ve)):
        tau = fitted_tau(step_samples(c.log, axis, target), target)
        log.info("velocity step %s -> %.1f m/s: fitted tau %.4f s", axis, target, tau)
        assert tau == pytest.approx(TAU, abs=TAU_TOLERANCE), axis


def _check_position(c: Client, north: float, east: float, alt: float) -> None:
    c.log.clear()
    start_n = c.last["LOCAL_POSITION_NED"].x
    near = c.stream_until(
        lambda: c.position(north, east, -alt),
        lambda m: _is_local(m) and math.hypot(m.x - north, m.y - east) < 0.1 and m.vx**2 < 0.01,
        20.0,
    )
    assert near is not None
    c.stream(lambda: c.position(north, east, -alt), 0.5)
    last = c.log[-1]
    assert math.hypot(last.x - north, last.y - east) < SETTLE_TOLERANCE
    assert -last.z == pytest.approx(alt, abs=SETTLE_TOLERANCE)
    direction = math.copysign(1.0, north - start_n)
    overshoot = max((m.x - north) * direction for m in c.log)
    err = math.hypot(last.x - north, last.y - east)
    log.info("position setpoint: settled within %.3f m, overshoot %.3f m", err, overshoot)
    assert overshoot < OVERSHOOT_TOLERANCE


@pytest.mark.timeout(90)
def test_pymavlink_flies_px4_persona_in_offboard_with_tau_lag_response() -> None:
    base = free_udp_base(2)
    with running_emulator(make_config(2, base, personas=("px4",))), Client(base + 1, 2) as c:
        assert c.pump(5, lambda m: m.get_type() == "HEARTBEAT") is not None
        c.heartbeat()
        assert c.set_param("MIS_TAKEOFF_ALT", 10.0) == 10.0
        assert c.command(400, 1) == 0
        assert c.command(22, *[math.nan] * 7) == 0
        assert c.pump(10, lambda m: _is_local(m) and m.z < -9.7)
        assert c.pump(5, lambda m: m.get_type() == "HEARTBEAT" and m.custom_mode == PX4_HOLD)
        # OFFBOARD without a setpoint stream is refused, as PX4 does.
        assert c.command(176, 1, 6, 0) == 2
        c.stream(lambda: c.velocity(0, 0), 0.3)
        assert c.command(176, 1, 6, 0) == 0
        assert c.pump(5, lambda m: m.get_type() == "HEARTBEAT" and m.custom_mode == PX4_OFFBOARD)
        _check_velocity_step(c, 8.0, -4.0)
        here = c.last["LOCAL_POSITION_NED"]
        _check_position(c, here.x + 120.0, here.y - 30.0, 15.0)


@pytest.mark.timeout(90)
def test_pymavlink_flies_ardupilot_persona_in_guided_with_tau_lag_response() -> None:
    base = free_udp_base(2)
    with running_emulator(make_config(2, base, personas=("ardupilot",))), Client(base, 1) as c:
        hb = c.pump(5, lambda m: m.get_type() == "HEARTBEAT")
        assert hb.autopilot == 3
        assert hb.custom_mode == 0  # STABILIZE at boot
        c.heartbeat()
        c.conn.mav.set_mode_send(1, 1, 4)
        assert c.pump(5, lambda m: m.get_type() == "COMMAND_ACK" and m.command == 11).result == 0
        assert c.command(400, 1) == 0
        assert c.command(22, 0, 0, 0, 0, 0, 0, 12.0) == 0
        assert c.pump(10, lambda m: _is_local(m) and m.z < -11.7)
        _check_velocity_step(c, -6.0, 9.0)
        here = c.last["LOCAL_POSITION_NED"]
        _check_position(c, here.x - 100.0, here.y + 50.0, 12.0)
        assert c.mode() == 4  # still GUIDED
