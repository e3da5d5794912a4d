"""The public API: ``fly(profile, vehicle, link, ...)`` flies one vehicle of the emulator (running
in this process, on its own thread) from a plain asyncio script, as `companion run` does."""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

from companion.fly import fly
from companion.link.pymavlink_link import PymavlinkLink
from companion.mission.phase import Phase
from companion.telemetry import events
from companion.telemetry.mission_log import read_log, read_records
from mdm_profiles.overrides import apply_overrides
from tests.emulator_harness import PROFILE, free_udp_base, make_config, running_emulator
from tests.waiting import wait_until_async


def _phases(log: Path) -> list[str]:
    return [e.phase for e in read_log(log).of(events.PhaseChange)]


def test_a_script_flies_a_mission_to_its_end(tmp_path: Path) -> None:
    base = free_udp_base(1)

    async def main() -> str:
        link = PymavlinkLink(url=f"udpin:127.0.0.1:{base}", target_system=1)
        async with fly(
            PROFILE, 0, link, log_dir=tmp_path, duration=20.0, land_wait=120.0
        ) as flight:
            return await asyncio.wait_for(flight.ended(), 90.0)

    with running_emulator(make_config(1, base, speedup=20.0)):
        reason = asyncio.run(main())
    assert reason == "mission time"
    assert _phases(tmp_path / "mission-0.jsonl") == [
        "prepare",
        "climb",
        "search",
        "return",
        "done",
    ]
    # The emulator keeps no autopilot log and says so (LOG_ENTRY, num_logs 0): the companion
    # asked for one, after the landing, and says why there is none.
    (kept,) = [r for r in read_records(tmp_path / "mission-0.jsonl") if r["event"] == "flight_log"]
    assert kept["path"] is None
    assert kept["note"] == "the vehicle holds no log"


def test_leaving_the_block_early_ends_with_the_end_action_and_waits(tmp_path: Path) -> None:
    base = free_udp_base(1)

    async def main() -> str:
        link = PymavlinkLink(url=f"udpin:127.0.0.1:{base}", target_system=1)
        async with fly(
            PROFILE, 0, link, log_dir=tmp_path, duration=600.0, land_wait=120.0
        ) as flight:
            await wait_until_async(
                lambda: flight.mission.phase,
                120.0,
                "the search",
                until=lambda phase: phase is Phase.SEARCH,
            )
        return await flight.ended()

    with running_emulator(make_config(1, base, speedup=20.0)):
        reason = asyncio.run(asyncio.wait_for(main(), 90.0))
    assert reason == "operator"
    logged = read_log(tmp_path / "mission-0.jsonl").events
    assert [e.event.reason for e in logged if isinstance(e.event, events.End)] == ["operator"]
    assert _phases(tmp_path / "mission-0.jsonl")[-2:] == ["return", "done"]
    end = next(k for k, e in enumerate(logged) if isinstance(e.event, events.End))
    # RTL after the end (the PX4 persona, as PX4, then holds once landed and disarmed)
    assert "RTL" in [e.event.mode for e in logged[end:] if isinstance(e.event, events.ModeChange)]


def test_a_flight_that_cannot_run_is_refused_before_anything_starts(tmp_path: Path) -> None:
    async def main() -> None:
        link = PymavlinkLink(url="udpin:127.0.0.1:9", target_system=99)
        async with fly(PROFILE, 98, link, log_dir=tmp_path):
            pass

    with pytest.raises(ValueError, match="vehicle 98: profile has 12 vehicles"):
        asyncio.run(main())
    assert not (tmp_path / "mission-98.jsonl").exists()


def test_a_study_only_redetection_rule_is_refused_naming_the_key(tmp_path: Path) -> None:
    """policy.redetection reads the detection sensor on the last level, which a live vehicle
    has switched off there: the companion refuses it before anything starts."""
    renewing = apply_overrides(PROFILE, ["policy.redetection=renew"])

    async def main() -> None:
        link = PymavlinkLink(url="udpin:127.0.0.1:9", target_system=1)
        async with fly(renewing, 0, link, log_dir=tmp_path):
            pass

    with pytest.raises(ValueError, match=r"policy\.redetection 'renew' .* set it to 'ignore'"):
        asyncio.run(main())
    assert not (tmp_path / "mission-0.jsonl").exists()
