"""MAVSDK 4's own plugins fly the emulator on both personas (tests/mavsdk_flights.py): a
QGroundControl plan with a Survey through mission_raw's QGC import (mission, fence and rally
point uploaded, the mission read back, flown to its RTL), the geofence plugin, offboard
position setpoints over the take-off point ending in a landing within a metre of where it was
asked, and a pilot's sticks through manual_control."""

from __future__ import annotations

import asyncio
import math

import pytest
from mavsdk.asyncio import Configuration, Mavsdk
from mavsdk.asyncio.plugins.geofence import FenceType, GeofenceAsync, GeofenceData, Point, Polygon

from tests.emulator_harness import free_udp_base, make_config, running_emulator
from tests.mavsdk_flights import (
    autopilot,
    fly_mission_plugin,
    fly_offboard_square,
    fly_plan,
    fly_sticks,
    upload_with_return,
)
from tests.qgc_plan import lawnmower, plan_text, survey_plan

PERSONAS = ["ardupilot", "px4"]
SURVEY = lawnmower(3, 80.0, 25.0, (20.0, -20.0))
"""Three 80 m legs 25 m apart: six turn points, north and east of home."""
PASS_RADIUS = 2.5
"""m: the flown path passes each survey point this close (the acceptance radius is 2 m)."""
LAND_ERROR = 1.0
"""m: where a vehicle must touch down, at most this far from where it was asked to."""


def _url(base: int) -> str:
    return f"udpin://127.0.0.1:{base}"


@pytest.mark.timeout(120)
@pytest.mark.parametrize("persona", PERSONAS)
def test_mavsdk_flies_a_qgroundcontrol_survey_plan(persona: str) -> None:
    base = free_udp_base(1)
    with running_emulator(make_config(1, base, personas=(persona,), speedup=10.0)) as emu:
        v = emu.vehicles[0]
        home = emu.telemetry.home_geo(v)
        ardupilot = persona == "ardupilot"
        plan = plan_text(survey_plan(home, SURVEY, 15.0, 3 if ardupilot else 12))
        rec = asyncio.run(fly_plan(_url(base), plan, ardupilot=ardupilot, speed=8.0))
        assert len(v.plans.fence.items) == 4
        assert len(v.plans.rally.items) == 1
    # takeoff, six survey points, RTL (+ ArduPilot's home item MAVSDK puts first)
    items = 8 + ardupilot
    assert rec.uploaded == (items, 4, 1)
    assert rec.downloaded == items
    assert rec.progress == sorted(rec.progress)
    assert rec.progress[-1] >= items - 1
    # The survey, before PX4's RTL climbs to RTL_RETURN_ALT (30 m) to fly home.
    climb = next((k for k, (_, _, a) in enumerate(rec.path) if a > 15.5), len(rec.path))
    survey = rec.path[:climb]
    for n, e in SURVEY:
        miss, alt = min((math.hypot(pn - n, pe - e), pa) for pn, pe, pa in survey)
        assert miss < PASS_RADIUS, (n, e, miss)
        assert alt == pytest.approx(15.0, abs=0.5)  # the survey's altitude (RTL climbs higher)
    assert rec.landed_at is not None
    # RTL lands at the nearest of home and the rally point (50 m north), as both autopilots
    # do: from the last survey point (100, 30) that is the rally point.
    assert math.hypot(rec.landed_at[0] - 50.0, rec.landed_at[1]) < LAND_ERROR


@pytest.mark.timeout(60)
@pytest.mark.parametrize("persona", PERSONAS)
def test_mavsdk_geofence_plugin_uploads_a_polygon(persona: str) -> None:
    base = free_udp_base(1)

    async def upload(lat: float, lon: float) -> int:
        async with Mavsdk(Configuration.create_manual(245, 190, True)) as mavsdk:
            system = await autopilot(mavsdk, _url(base))
            fence = GeofenceAsync(system)
            d = 0.001
            corners = [
                (lat - d, lon - d),
                (lat - d, lon + d),
                (lat + d, lon + d),
                (lat + d, lon - d),
            ]
            polygon = Polygon([Point(a, b) for a, b in corners], FenceType.INCLUSION)
            await fence.upload_geofence(GeofenceData([polygon], []))
            return len(corners)

    with running_emulator(make_config(1, base, personas=(persona,))) as emu:
        v = emu.vehicles[0]
        lat, lon, _ = emu.telemetry.home_geo(v)
        count = asyncio.run(upload(lat, lon))
        assert [it.command for it in v.plans.fence.items] == [5001] * count


@pytest.mark.timeout(90)
@pytest.mark.parametrize("persona", PERSONAS)
def test_mavsdk_offboard_position_square_lands_where_asked(persona: str) -> None:
    base = free_udp_base(1)
    with running_emulator(make_config(1, base, personas=(persona,), speedup=10.0)) as emu:
        rec = asyncio.run(
            fly_offboard_square(
                _url(base), 10.0, 5.0, ardupilot=persona == "ardupilot", settle_s=1.5
            )
        )
        v = emu.vehicles[0]
        truth = (v.fleet.pos[0, 0] - v.origin[0], v.fleet.pos[0, 1] - v.origin[1])
    for got, want in zip(rec.corners, [(10, 0), (10, 10), (0, 10), (0, 0)], strict=True):
        assert math.hypot(got[0] - want[0], got[1] - want[1]) < 0.5, (got, want)
    assert math.hypot(*rec.landed_at) < LAND_ERROR
    assert math.hypot(*truth) < LAND_ERROR  # the emulator's own state, not the client's view


@pytest.mark.timeout(60)
@pytest.mark.parametrize("persona", PERSONAS)
def test_mavsdk_manual_control_flies_in_position_mode_and_holds_when_centred(
    persona: str,
) -> None:
    base = free_udp_base(1)
    with running_emulator(make_config(1, base, personas=(persona,), speedup=10.0)):
        rec = asyncio.run(fly_sticks(_url(base), seconds=1.0))
    # Only a pilot mode (POSCTL, LOITER/POSHOLD) moves on sticks: HOLD would stay put.
    north, east = rec.moved
    assert north > 50.0  # about 10 sim s of full pitch forward, heading north
    assert abs(east) < 1.0
    assert rec.drift_after_release < 1.0


@pytest.mark.timeout(90)
@pytest.mark.parametrize("persona", PERSONAS)
def test_mavsdk_mission_plugin_flies_waypoints_and_returns(persona: str) -> None:
    base = free_udp_base(1)
    points = [(40.0, 0.0), (40.0, 40.0), (0.0, 40.0)]
    with running_emulator(make_config(1, base, personas=(persona,), speedup=10.0)):
        progress, count, landed = asyncio.run(
            fly_mission_plugin(_url(base), points, 12.0, ardupilot=persona == "ardupilot")
        )
    assert count == 3
    assert progress == sorted(progress)
    # The last waypoint, then the return (MAVSDK's RTL item), or past it: MAVSDK's "current ==
    # total, the mission is finished" (ArduPilot: MISSION_CURRENT asked for after the upload).
    assert progress[-1] in (count - 1, count), progress
    assert math.hypot(*landed) < LAND_ERROR  # the return to launch after the mission


@pytest.mark.timeout(60)
@pytest.mark.parametrize(
    ("persona", "answer"), [("ardupilot", "INVALID_ARGUMENT"), ("px4", "SUCCESS")]
)
def test_mavsdk_return_after_mission_is_refused_as_arducopter_refuses_it(
    persona: str, answer: str
) -> None:
    # MAVSDK sends the return as NAV_RETURN_TO_LAUNCH with NaN params: ArduCopter answers
    # MISSION_ACK INVALID_PARAM1 (tests/sim_vehicle_stub/test_svs_mission_plugin_differential.py).
    base = free_udp_base(1)
    with running_emulator(make_config(1, base, personas=(persona,), speedup=10.0)):
        got = asyncio.run(upload_with_return(_url(base), [(40.0, 0.0), (40.0, 40.0)], 12.0))
    assert got == answer
