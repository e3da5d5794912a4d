"""MAVSDK 4's telemetry plugin reads the emulator on both personas as a ground station does:
every subscription of tests/mavsdk_telemetry.py delivers, with the values of a vehicle standing
disarmed at its home (the profile's origin)."""

from __future__ import annotations

import asyncio
import math

import pytest

from tests.emulator_harness import PROFILE, free_udp_base, make_config, running_emulator
from tests.mavsdk_telemetry import SUBSCRIPTIONS, first_values

MODE = {"ardupilot": "STABILIZED", "px4": "HOLD"}
"""MAVSDK's name of each persona's boot mode (ArduCopter STABILIZE, PX4 HOLD)."""


@pytest.mark.timeout(60)
@pytest.mark.parametrize("persona", ["ardupilot", "px4"])
def test_mavsdk_telemetry_subscriptions_all_deliver(persona: str) -> None:
    base = free_udp_base(1)
    cfg = make_config(1, base, personas=(persona,), speedup=5.0, start_positions=((0.0, 0.0),))
    with running_emulator(cfg):
        got = asyncio.run(first_values(f"udpin://127.0.0.1:{base}"))
    missing = [n for n in SUBSCRIPTIONS if got[n] is None]
    assert not missing, missing
    assert got["health"].is_global_position_ok
    assert got["health"].is_home_position_ok
    home, pos = got["home"], got["position"]
    assert (
        math.hypot(home.latitude_deg - PROFILE.origin.lat, home.longitude_deg - PROFILE.origin.lon)
        < 1e-5
    )
    assert abs(pos.relative_altitude_m) < 1.0
    assert got["gps_info"].num_satellites > 5
    assert got["gps_info"].fix_type.name in ("FIX_3D", "FIX_DGPS", "RTK_FLOAT", "RTK_FIXED")
    assert 0.5 < got["battery"].remaining_percent <= 100.0
    assert got["armed"] is False
    assert got["in_air"] is False
    assert got["landed_state"].name == "ON_GROUND"
    assert math.hypot(got["velocity_ned"].north_m_s, got["velocity_ned"].east_m_s) < 0.5
    assert abs(got["fixedwing_metrics"].groundspeed_m_s) < 0.5
    assert got["flight_mode"].name == MODE[persona]
