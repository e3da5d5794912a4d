"""The exit rule of a companion (companion/mission/mission_exit.py): 0 only for a vehicle seen
disarmed after a mission that no fault cut short."""

from __future__ import annotations

import pytest

from companion.autopilots import autopilot_for
from companion.link.messages import Heartbeat
from companion.mission.mission_exit import FAULT_ENDS, MissionExit, final_exit

PX4 = 12
DISARMED = Heartbeat(autopilot=PX4, custom_mode=0, armed=False, system_status=3)
ARMED = Heartbeat(autopilot=PX4, custom_mode=0, armed=True, system_status=4)
LANDED = MissionExit(0, "RTL: landed and disarmed")


@pytest.mark.parametrize("reason", ["mission time", "all targets", "operator abort", None])
def test_a_mission_that_ended_normally_and_landed_exits_0(reason: str | None) -> None:
    assert final_exit(LANDED, DISARMED, autopilot_for(PX4), "at 0 m", None, reason) == LANDED
    assert final_exit(None, DISARMED, autopilot_for(PX4), "at 0 m", None, reason).status == 0


@pytest.mark.parametrize(
    "reason",
    ["climb timeout", "transit not done in 300 s", "outside the fence: 40 m", "battery 19%"],
)
def test_a_mission_cut_short_by_a_fault_exits_1_naming_it_however_it_came_down(reason: str) -> None:
    assert reason.startswith(FAULT_ENDS)
    for exit in (LANDED, None):
        got = final_exit(exit, DISARMED, autopilot_for(PX4), "at 0 m", None, reason)
        assert got.status == 1
        assert got.cause.startswith(f"{reason}; ")


def test_a_vehicle_left_armed_or_never_heard_exits_1() -> None:
    armed = final_exit(None, ARMED, autopilot_for(PX4), "at 30 m, 1.2 km from home", None)
    assert armed.status == 1
    assert armed.cause.endswith("at 30 m, 1.2 km from home")
    assert final_exit(None, None, None, "position never known", None).status == 1


def test_the_position_failsafe_makes_a_landing_exit_1() -> None:
    got = final_exit(LANDED, DISARMED, autopilot_for(PX4), "at 0 m", "no valid position for 12 s")
    assert got == MissionExit(1, "failsafe (no valid position for 12 s); RTL: landed and disarmed")
