"""The durable mission log: what a restarted companion recovers, torn lines tolerated."""

from __future__ import annotations

from pathlib import Path

from companion.mission.clock import VehicleClock
from companion.telemetry import MissionLog, read_log


def test_restart_recovers_confirmations_and_search_start(tmp_path: Path) -> None:
    path = tmp_path / "mission-0.jsonl"
    log = MissionLog(path)
    log.emit(12.0, "phase", phase="search", search_start=12.0)
    log.emit(40.0, "confirmation", north=100.0, east=200.0, level=1, found=1)
    log.emit(90.5, "tick", level=0)
    log.close()
    with path.open("a") as f:
        f.write('{"t": 91, "event": "confirm')  # killed mid-write
    got = read_log(path)
    assert got.confirmed == [(100.0, 200.0)]
    assert got.search_start == 12.0
    assert got.last_time == 90.5
    assert not got.ended


def test_missing_log_recovers_nothing(tmp_path: Path) -> None:
    got = read_log(tmp_path / "none.jsonl")
    assert got.confirmed == []
    assert got.search_start is None


def test_clock_stays_monotonic_across_vehicle_reboot_and_companion_restart() -> None:
    clock = VehicleClock(floor=100.0)
    assert clock.update(5.0) == 100.0  # vehicle rebooted while the companion was down
    assert clock.update(6.0) == 101.0
    assert clock.update(0.5) == 101.0  # reboot mid-flight
    assert clock.update(2.5) == 103.0
