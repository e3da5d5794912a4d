"""The durable mission log: what a restarted companion recovers, torn lines tolerated."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from companion.mission.vehicle_clock import VehicleClock
from companion.telemetry import MissionLog, events, read_log, read_records
from companion.telemetry.events import LogFormatError
from companion.telemetry.mission_log import Logged


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
        events.TelemetryDropped("non-finite", 3, 7),
        events.SetpointRefused("speed", "speed 30 m/s above the profile's 20", 1),
        events.AltitudeLayer("outside", 47.3, 40.0, 2.0),
        events.Exit(1, "link lost while armed"),
    ]
    assert {type(e) for e in written} == set(events.DURABLE.values())
    path = tmp_path / "mission-0.jsonl"
    log = MissionLog(path)
    for i, event in enumerate(written):
        log.emit(float(i), event.NAME, **events.to_fields(event))
    log.close()
    records = read_records(path)
    assert [events.from_record(r) for r in records] == written
    assert [(e.t, e.event) for e in read_log(path).events] == list(enumerate(written))
    assert "by" not in records[1]  # optional fields left out when None, as before
    got = read_log(path)
    assert got.confirmed == [(100.0, 200.0)]
    assert got.search_start == 12.0
    assert got.ended
    assert got.starts == 1


def test_a_record_of_another_event_is_not_a_durable_event() -> None:
    assert events.from_record({"t": 1.0, "event": "tick", "level": 0}) is None


@pytest.mark.parametrize(
    ("line", "message"),
    [
        (  # a required field renamed
            {"event": "confirmation", "n": 100.0, "east": 200.0, "level": 1, "found": 1},
            "'confirmation' record has field 'n', which Confirmation does not know",
        ),
        (  # a required field missing
            {"event": "end", "found": 1},
            "'end' record lacks field 'reason' (End)",
        ),
        (  # an optional field renamed: it would otherwise read back as None
            {"event": "phase", "phase": "search", "search_begin": 12.0},
            "'phase' record has field 'search_begin'",
        ),
        (  # a field of another type
            {"event": "level", "level": "2", "sensor": 1},
            "'level' record field 'level' is '2', not int",
        ),
        (  # JSON's true is no level
            {"event": "level", "level": True, "sensor": 1},
            "'level' record field 'level' is True, not int",
        ),
        ({"event": "tick", "t": "soon"}, "field 't' is 'soon', not a number"),
    ],
)
def test_a_log_of_another_shape_is_refused_naming_file_line_and_field(
    tmp_path: Path, line: dict[str, object], message: str
) -> None:
    path = tmp_path / "mission-0.jsonl"
    MissionLog(path).emit(1.0, "start", **events.to_fields(events.Start(0, "p", 5, 0, 30.0)))
    with path.open("a") as f:
        f.write(json.dumps({"t": 2.0} | line) + "\n")
    with pytest.raises(LogFormatError) as refused:
        read_log(path)
    assert str(refused.value).startswith(f"{path}:2: ")
    assert message in str(refused.value)


def test_an_integer_where_a_float_was_written_reads_back(tmp_path: Path) -> None:
    path = tmp_path / "mission-0.jsonl"
    path.write_text('{"t":3,"event":"confirmation","north":100,"east":200,"level":1,"found":1}\n')
    (logged,) = read_log(path).events
    assert logged == Logged(3.0, events.Confirmation(100, 200, 1, 1))
