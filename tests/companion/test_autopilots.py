"""Mode encodings of PX4 and ArduPilot as measured (MAVLINK_NOTES.md), and the registry."""

from __future__ import annotations

import pytest

from companion.autopilots import PX4, ArduCopter, FlightMode, UnknownAutopilotError, autopilot_for


def test_px4_custom_modes_match_the_real_encoding() -> None:
    px4 = PX4()
    assert px4.custom_mode(FlightMode.GUIDED) == 0x60000
    assert px4.custom_mode(FlightMode.HOLD) == 0x3040000
    assert px4.custom_mode(FlightMode.RTL) == 0x5040000
    assert px4.custom_mode(FlightMode.LAND) == 0x6040000
    assert px4.mode_name(0x60000) == "OFFBOARD"
    cmd = px4.mode_command(FlightMode.RTL, armed=True)
    assert (cmd.base_mode, cmd.custom_main, cmd.custom_sub) == (129.0, 4.0, 5.0)
    # Offboard loss: HOLD (COM_OBL_RC_ACT 5) or POSCTL (stock 0, seen on PX4 SITL); not RTL.
    assert px4.is_fallback(0x3040000)
    assert px4.is_fallback(0x30000)
    assert not px4.is_fallback(0x5040000)


def test_ardupilot_guided_is_mode_4_and_takes_off_by_command() -> None:
    ap = ArduCopter()
    assert ap.custom_mode(FlightMode.GUIDED) == 4
    assert ap.is_guided(4)
    assert not ap.is_guided(5)
    assert ap.is_fallback(17)
    assert not ap.is_fallback(5)
    assert ap.takeoff_by_command
    assert not PX4.takeoff_by_command
    assert ap.takeoff_params(35.0)[6] == 35.0


def test_registry_picks_by_heartbeat_autopilot_and_names_unknown_ones() -> None:
    assert isinstance(autopilot_for(12), PX4)
    assert isinstance(autopilot_for(3), ArduCopter)
    with pytest.raises(UnknownAutopilotError, match="known: 3 \\(ardupilot\\), 12 \\(px4\\)"):
        autopilot_for(8)
