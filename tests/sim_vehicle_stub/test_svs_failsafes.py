"""Failsafes as the real autopilots have them, over real UDP with pymavlink."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import pytest

from tests.emulator_harness import Client, free_udp_base, make_config, running_emulator

PX4_HOLD, PX4_RTL, PX4_OFFBOARD, PX4_POSCTL = 0x3040000, 0x5040000, 0x60000, 0x30000
AP_GUIDED, AP_RTL = 4, 6


def _px4_airborne(c: Client, alt: float = 10.0) -> None:
    assert c.pump(5, lambda m: m.get_type() == "HEARTBEAT") is not None
    c.heartbeat()
    assert c.set_param("MIS_TAKEOFF_ALT", alt) == alt
    assert c.command(400, 1) == 0
    assert c.command(22, *[math.nan] * 7) == 0
    assert c.pump(10, lambda m: m.get_type() == "LOCAL_POSITION_NED" and m.z < -(alt - 0.3))
    assert c.pump(5, lambda m: m.get_type() == "HEARTBEAT" and m.custom_mode == PX4_HOLD)


def _ap_guided_airborne(c: Client, alt: float = 10.0) -> None:
    assert c.pump(5, lambda m: m.get_type() == "HEARTBEAT") is not None
    c.heartbeat()
    assert c.command(176, 1, AP_GUIDED) == 0
    assert c.command(400, 1) == 0
    assert c.command(22, 0, 0, 0, 0, 0, 0, alt) == 0
    assert c.pump(10, lambda m: m.get_type() == "LOCAL_POSITION_NED" and m.z < -(alt - 0.3))


def _heartbeat_is(mode: int) -> Callable[[Any], bool]:
    return lambda m: m.get_type() == "HEARTBEAT" and m.custom_mode == mode


@pytest.mark.timeout(60)
@pytest.mark.parametrize(("action", "mode"), [(0, PX4_POSCTL), (5, PX4_HOLD)])
def test_px4_offboard_setpoint_loss_switches_mode_after_com_of_loss_t(
    action: int, mode: int
) -> None:
    """Stock COM_OBL_RC_ACT 0: POSCTL, as PX4 SITL did when its companion was killed; 5: HOLD."""
    base = free_udp_base(1)
    with running_emulator(make_config(1, base)) as emu, Client(base, 1) as c:
        _px4_airborne(c)
        assert c.set_param("COM_OF_LOSS_T", 5.0) == 5.0  # sim seconds
        if action != 0:  # 0 is the default
            assert c.set_param("COM_OBL_RC_ACT", action, int_bytewise=True) is not None
        assert emu.vehicles[0].params.get("COM_OBL_RC_ACT") == action
        c.stream(lambda: c.velocity(5, 0), 0.3)
        assert c.command(176, 1, 6, 0) == 0
        assert c.stream_until(lambda: c.velocity(5, 0), _heartbeat_is(PX4_OFFBOARD), 5.0)
        c.stream(lambda: c.velocity(5, 0), 0.3)
        # The vehicle's own mode, not the next HEARTBEAT: an early beat may wait half an
        # interval (sim_vehicle_stub/node.py), which is not the time-out measured here.
        assert c.pump(5, lambda m: emu.vehicles[0].mode.custom_mode == mode) is not None
        setpoint = emu.vehicles[0].setpoint
        assert setpoint is not None
        lost_after = c.last["LOCAL_POSITION_NED"].time_boot_ms / 1000 - setpoint.t
        assert 5.0 - 0.15 <= lost_after <= 5.0 + 0.25  # the time-out, within a tick or two
        assert c.pump(2, _heartbeat_is(mode)) is not None  # and the clients are told
        assert c.pump(5, lambda m: m.get_type() == "LOCAL_POSITION_NED" and abs(m.vx) < 0.2)


@pytest.mark.timeout(60)
def test_ardupilot_guided_velocity_timeout_stops_the_vehicle_in_guided() -> None:
    base = free_udp_base(1)
    cfg = make_config(1, base, personas=("ardupilot",))
    with running_emulator(cfg) as emu, Client(base, 1) as c:
        _ap_guided_airborne(c)
        assert c.set_param("GUID_TIMEOUT", 5.0) == 5.0
        fast = c.stream_until(
            lambda: c.velocity(0, 6),
            lambda m: m.get_type() == "LOCAL_POSITION_NED" and abs(m.vy - 6.0) < 0.05,
            10.0,
        )
        assert fast is not None
        setpoint = emu.vehicles[0].setpoint
        assert setpoint is not None
        stopped = c.pump(5, lambda m: m.get_type() == "LOCAL_POSITION_NED" and abs(m.vy) < 0.2)
        assert stopped is not None
        # Braking starts at the time-out (5 sim s after the last setpoint) and takes ~1 s.
        assert 5.0 < stopped.time_boot_ms / 1000 - setpoint.t < 5.0 + 2.0
        assert c.mode() == AP_GUIDED


@pytest.mark.timeout(60)
def test_px4_data_link_loss_runs_nav_dll_act_and_rtl_lands_and_disarms() -> None:
    base = free_udp_base(1)
    with running_emulator(make_config(1, base)) as emu, Client(base, 1) as c:
        _px4_airborne(c, 8.0)
        assert c.set_param("NAV_DLL_ACT", 2, int_bytewise=True) is not None
        assert emu.vehicles[0].params.get("NAV_DLL_ACT") == 2
        assert c.set_param("COM_DL_LOSS_T", 5, int_bytewise=True) is not None
        assert c.set_param("RTL_RETURN_ALT", 10.0) == 10.0
        assert c.set_param("MPC_LAND_SPEED", 3.0) == 3.0
        c.heartbeat()
        # No more heartbeats from here on: after 5 sim s the link counts as lost.
        assert c.pump(10, _heartbeat_is(PX4_RTL)) is not None
        assert c.pump(10, lambda m: m.get_type() == "HEARTBEAT" and not m.base_mode & 128)
        c.pump(0.3)
        assert -c.last["LOCAL_POSITION_NED"].z < 0.1


@pytest.mark.timeout(60)
def test_ardupilot_geofence_breach_runs_fence_action_rtl() -> None:
    base = free_udp_base(1)
    cfg = make_config(1, base, personas=("ardupilot",), start_positions=((60.0, 5000.0),))
    with running_emulator(cfg), Client(base, 1) as c:
        _ap_guided_airborne(c)
        assert c.set_param("MDM_FENCE_MARG", 20.0) == 20.0
        c.log.clear()
        assert c.stream_until(lambda: c.velocity(-10, 0), _heartbeat_is(AP_RTL), 10.0)
        c.pump(1.0)
        # Area starts at north 0, fence at -20 m: it turned back within a few metres of it.
        # LOCAL_POSITION_NED is from the boot point, 60 m north of the area's edge.
        assert min(m.x for m in c.log) + 60.0 < -20.0
        assert min(m.x for m in c.log) + 60.0 > -35.0


@pytest.mark.timeout(60)
def test_low_battery_triggers_px4_return() -> None:
    base = free_udp_base(1)
    with running_emulator(make_config(1, base, battery_endurance=40.0)), Client(base, 1) as c:
        _px4_airborne(c)
        first = c.last["BATTERY_STATUS"].battery_remaining
        assert c.pump(15, _heartbeat_is(PX4_RTL)) is not None
        c.pump(0.3)
        remaining = c.last["BATTERY_STATUS"].battery_remaining
        assert remaining < first
        assert remaining <= 8  # BAT_CRIT_THR 0.07
