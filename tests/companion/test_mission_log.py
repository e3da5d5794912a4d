"""The durable mission log: what a restarted companion recovers, torn lines tolerated."""

from __future__ import annotations

from pathlib import Path

from companion.mission.clock import VehicleClock
from companion.telemetry import MissionLog, events, read_log, read_records


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


def test_every_durable_event_reads_back_as_written(tmp_path: Path) -> None:
    written: list[events.DurableEvent] = [
        events.Start(0, "paper-fixed", 5, 1, 30.0),
        events.PhaseChange("search", search_start=12.0),
        events.PhaseChange("paused", by="operator"),
        events.Level(1, 1),
        events.Detection(10.0, 20.0, 0),
        events.Confirmation(100.0, 200.0, 1, 1),
        events.Fallback(0),
        events.ModeChange("OFFBOARD", True),
        events.LinkState("lost", 3.2),
        events.LinkState("restored"),
        events.End("mission time", 1),
    ]
    assert {type(e) for e in written} == set(events.DURABLE.values())
    path = tmp_path / "mission-0.jsonl"
    log = MissionLog(path)
    for i, event in enumerate(written):
        log.emit(float(i), event.NAME, **events.to_fields(event))
    log.close()
    records = read_records(path)
    assert [events.from_record(r) for r in records] == written
    assert "by" not in records[1]  # optional fields left out when None, as before
    got = read_log(path)
    assert got.confirmed == [(100.0, 200.0)]
    assert got.search_start == 12.0
    assert got.ended
    assert got.starts == 1


def test_a_record_missing_a_field_is_not_taken_for_the_event() -> None:
    renamed = {"t": 1.0, "event": "confirmation", "n": 100.0, "east": 200.0, "level": 1, "found": 1}
    assert events.from_record(renamed) is None
    assert events.from_record({"t": 1.0, "event": "tick", "level": 0}) is None
