"""The battery reserve counts the way home at the autopilot's own return speed where that is
slower than the profile's (companion/mission/return_speed.py): read before the first arm from
the emulator's personas, whose parameters are those of the real autopilots (PX4 MPC_XY_CRUISE,
ArduCopter RTL_SPEED, 0: WPNAV_SPEED), and recorded in the mission log."""

from __future__ import annotations

from pathlib import Path

import pytest

from companion.mission.battery_reserve import reserve_rule
from companion.telemetry.mission_log import read_records
from tests.companion.test_safety_net import FIELD, INSIDE, _arm_and_stop
from tests.emulator_harness import free_udp_base, make_config, running_emulator

RULE = reserve_rule(FIELD.site, FIELD.fleet.speed, "rtl")


def _return_speed(log_dir: Path) -> dict[str, object]:
    (found,) = [
        r for r in read_records(log_dir / "mission-0.jsonl") if r["event"] == "return_speed"
    ]
    return found


@pytest.mark.timeout(120)
@pytest.mark.parametrize(
    ("persona", "cruise", "param", "speed"),
    [
        ("px4", None, "MPC_XY_CRUISE", 5.0),  # PX4's stock: slower than the profile's 10 m/s
        ("px4", 12.0, "MPC_XY_CRUISE", 12.0),
        ("ardupilot", None, "WPNAV_SPEED", 10.0),  # no RTL_SPEED set: WPNAV_SPEED, cm/s
    ],
)
def test_the_reserve_counts_the_autopilots_own_return_speed(
    persona: str, cruise: float | None, param: str, speed: float, tmp_path: Path
) -> None:
    base = free_udp_base(1)
    config = make_config(
        1, base, profile=FIELD, speedup=20.0, personas=(persona,), start_positions=INSIDE
    )
    with running_emulator(config) as emu:
        if cruise is not None:
            emu.vehicles[0].params.set("MPC_XY_CRUISE", cruise)
            emu.vehicles[0].apply_params()
        _arm_and_stop(FIELD, base, tmp_path, battery_reserve=RULE)  # as `companion run` builds it
    assert RULE is not None
    got = _return_speed(tmp_path)
    assert (got["param"], got["speed"]) == (param, speed)
    assert got["counted"] == min(speed, RULE.horizontal)
