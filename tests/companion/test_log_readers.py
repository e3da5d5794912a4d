"""The fleet's progress, a vehicle's end and the run map read the durable events typed from the
same mission log the companion writes (MissionLog and the event classes), ticks as records."""

from __future__ import annotations

from pathlib import Path

import pytest

from companion.telemetry import MissionLog, events
from companion.telemetry.events import LogFormatError
from mdm_ground.fleet.outcome import vehicle_end
from mdm_ground.fleet.progress import read_progress
from mdm_ground.run_map.tracks import Sample, read_track


def _log(path: Path, logged: list[tuple[float, events.DurableEvent]]) -> None:
    log = MissionLog(path)
    for t, event in logged:
        log.emit(t, event.NAME, **events.to_fields(event))
    log.close()


def test_progress_end_and_track_of_one_searched_log(tmp_path: Path) -> None:
    path = tmp_path / "mission-0.jsonl"
    _log(
        path,
        [
            (0.0, events.Start(0, "paper-fixed", 1, 0, 30.0)),
            (12.0, events.PhaseChange("search", search_start=12.0)),
            (30.0, events.Detection(100.0, 200.0, 1)),
            (30.0, events.Level(1, 1)),
            (41.0, events.Confirmation(101.0, 199.0, 1, 1)),
            (41.0, events.Level(0, 0)),
            (50.0, events.PhaseChange("return")),
        ],
    )
    log = MissionLog(path)
    log.emit(55.5, "tick", phase="return", level=0, north=5.0, east=6.0, alt=30.0, found=1)
    log.emit(56.0, "stray", address="127.0.0.1:5", locked="127.0.0.1:4")
    log.close()
    (view,) = read_progress(tmp_path, 1)
    assert (view.time, view.level, view.phase, view.found) == (56.0, 0, "return", 1)
    assert view.letter() == "R"
    track = read_track(path, 0)
    assert track.path == [Sample(55.5, 5.0, 6.0)]
    assert track.detections == [(Sample(30.0, 100.0, 200.0), 1)]
    assert track.confirmations == [Sample(41.0, 101.0, 199.0)]
    assert track.end_reason is None
    running = vehicle_end(tmp_path, 0, 1, None)
    assert (running.how, running.ok) == ("no end in its mission log, exit code 1", False)
    assert running.strays == ("127.0.0.1:5 (locked to 127.0.0.1:4)",)
    _log(path, [(60.0, events.End("mission time", 1))])
    ended = vehicle_end(tmp_path, 0, 0, None)
    assert (ended.how, ended.ok) == ("mission time", True)
    assert read_track(path, 0).end_reason == "mission time"


def test_progress_refuses_a_log_another_version_wrote(tmp_path: Path) -> None:
    path = tmp_path / "mission-0.jsonl"
    path.write_text('{"t":30.0,"event":"level","lvl":1,"sensor":1}\n')
    with pytest.raises(LogFormatError, match="'level' record has field 'lvl'"):
        read_progress(tmp_path, 1)
