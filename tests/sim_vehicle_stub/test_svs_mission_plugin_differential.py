"""Differential test of MAVSDK's mission plugin (not mission_raw) on ArduCopter: the emulator's
ArduPilot persona and ArduCopter SITL must refuse the same upload (the plugin's return to
launch after the mission: NAV_RETURN_TO_LAUNCH with NaN params, MISSION_ACK INVALID_PARAM1,
MAVSDK's INVALID_ARGUMENT) and fly the same plan without it the same way (the same mission
progress, home again within LANDING_AGREEMENT)."""

from __future__ import annotations

import asyncio
import math
from collections.abc import Callable

import pytest

from companion.link.address import parse_address
from tests.emulator_harness import PROFILE, free_udp_base, make_config, running_emulator
from tests.mavsdk_flights import fly_mission_plugin, upload_with_return
from tests.sitl import SitlInstance

HOME = f"{PROFILE.origin.lat},{PROFILE.origin.lon},{PROFILE.origin.alt},0"
POINTS = [(40.0, 0.0), (40.0, 40.0), (0.0, 40.0)]
ALT = 12.0
SPEEDUP = 3.0
LANDING_AGREEMENT = 3.0
"""m between where the two touch down after Action's return to launch."""


def _both(url: str) -> tuple[str, tuple[list[int], int, tuple[float, float]]]:
    refused = asyncio.run(upload_with_return(url, POINTS, ALT))
    return refused, asyncio.run(fly_mission_plugin(url, POINTS, ALT, ardupilot=True))


@pytest.mark.timeout(400)
def test_mavsdk_mission_plugin_is_refused_and_flown_as_arducopter_does(
    arducopter: Callable[..., SitlInstance],
) -> None:
    base = free_udp_base(1)
    cfg = make_config(1, base, personas=("ardupilot",), speedup=SPEEDUP, start_positions=((0, 0),))
    with running_emulator(cfg):
        emulated = _both(f"udpin://127.0.0.1:{base}")
    inst = arducopter(home=HOME, speedup=SPEEDUP)
    real = _both(parse_address(inst.companion_url).mavsdk_url())
    print(f"\nmission plugin: emulator {emulated}; ArduCopter SITL {real}")
    assert emulated[0] == real[0] == "INVALID_ARGUMENT"
    (e_progress, e_count, e_landed), (r_progress, r_count, r_landed) = emulated[1], real[1]
    assert e_count == r_count == len(POINTS)
    assert e_progress == r_progress, inst.log()[-1500:]
    assert math.dist(e_landed, r_landed) < LANDING_AGREEMENT
