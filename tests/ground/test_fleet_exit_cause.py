"""The fleet's end table tells how a companion left its vehicle: the mission log's ``exit``
record, when not 0, follows the end reason and makes the vehicle's end not normal."""

from __future__ import annotations

from pathlib import Path

from companion.telemetry import events
from companion.telemetry.mission_log import MissionLog
from mdm_ground.fleet.outcome import vehicle_end


def _log(out: Path, *logged: events.DurableEvent) -> None:
    log = MissionLog(out / "mission-0.jsonl")
    for t, event in enumerate(logged):
        log.emit(float(t), event.NAME, **events.to_fields(event))
    log.close()


def test_a_non_zero_exit_is_named_in_the_table(tmp_path: Path) -> None:
    cause = "link lost while armed (no heartbeat for 30 s), RTL under way at 30 m, 1.2 km from home"
    _log(tmp_path, events.End("mission time", 1), events.Exit(1, cause))
    end = vehicle_end(tmp_path, 0, 1, None)
    assert end.how == f"mission time: {cause}, exit code 1"
    assert not end.ok


def test_a_zero_exit_keeps_the_end_reason(tmp_path: Path) -> None:
    _log(tmp_path, events.End("mission time", 1), events.Exit(0, "RTL: landed and disarmed"))
    end = vehicle_end(tmp_path, 0, 0, None)
    assert end.how == "mission time"
    assert end.ok
