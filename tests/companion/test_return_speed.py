"""The battery reserve counts the way home at the autopilot's own return speed where that is
slower than the profile's (companion/mission/return_speed.py): read before the first arm from
the emulator's personas, whose parameters are those of the real autopilots (PX4 MPC_XY_CRUISE,
ArduCopter RTL_SPEED, 0: WPNAV_SPEED), and recorded in the mission log."""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

from companion.fly import fly
from companion.link.pymavlink_link import PymavlinkLink
from companion.mission.battery_reserve import reserve_rule
from companion.telemetry.mission_log import read_records
from tests.companion.test_safety_net import FIELD, INSIDE
from tests.emulator_harness import free_udp_base, make_config, running_emulator
from tests.waiting import wait_until_async

RULE = reserve_rule(FIELD.site, FIELD.fleet.speed, "rtl")


def _arm_and_stop(base: int, log_dir: Path) -> None:
    """Fly vehicle 0 with the site's reserve rule (as `companion run` builds it) until armed."""

    async def main() -> None:
        link = PymavlinkLink(url=f"udpin:127.0.0.1:{base}", target_system=1)
        async with fly(
            FIELD, 0, link, log_dir=log_dir, land_wait=0.0, sensor_source="virtual",
            battery_reserve=RULE,
        ) as flight:  # fmt: skip
            await wait_until_async(
                lambda: (flight.mission.seen.heartbeat, flight.mission.end_reason),
                60.0,
                "armed or ended",
                until=lambda s: s[1] is not None or (s[0] is not None and s[0].armed),
            )
            flight.stop()
            await asyncio.wait_for(flight.ended(), 60.0)

    asyncio.run(main())


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
        _arm_and_stop(base, tmp_path)
    assert RULE is not None
    got = _return_speed(tmp_path)
    assert (got["param"], got["speed"]) == (param, speed)
    assert got["counted"] == min(speed, RULE.horizontal)
