"""Fleet scoring: confirmations against the profile (fixed targets) or the emulator's ground truth."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from companion.telemetry import MissionLog, events
from companion.telemetry.events import LogFormatError
from mdm_ground.fleet.scoring import EMULATOR_EVENTS, score
from mdm_profiles import builtin_profile


def _write(path: Path, records: list[dict[str, Any]]) -> None:
    path.write_text("".join(json.dumps(r) + "\n" for r in records))


def _mission(path: Path, confirmations: list[tuple[float, float, float]]) -> None:
    log = MissionLog(path)
    logged: list[tuple[float, events.DurableEvent]] = [
        (10.0, events.PhaseChange("search", search_start=10.0))
    ]
    logged += [(t, events.Confirmation(n, e, 1, k)) for k, (t, n, e) in enumerate(confirmations, 1)]
    for t, event in logged:
        log.emit(t, event.NAME, **events.to_fields(event))
    log.close()


def test_fixed_targets_without_an_emulator_log_use_the_profile_positions(tmp_path: Path) -> None:
    profile = builtin_profile("paper-fixed")
    first = profile.targets[0]
    _mission(
        tmp_path / "mission-0.jsonl",
        [(110.0, first.north + 300.0, first.east), (210.0, 10_000.0, 600.0)],
    )
    result = score(profile, tmp_path, vehicles=1, duration=1000.0)
    real, wrong = result.confirmations
    assert (real.target, real.real, real.time) == (0, True, 100.0)
    assert real.distance == pytest.approx(300.0)
    assert not wrong.real
    assert (result.tnc, result.false_confirmations) == (1, 1)


def test_moving_targets_need_the_emulator_log(tmp_path: Path) -> None:
    _mission(tmp_path / "mission-0.jsonl", [])
    with pytest.raises(FileNotFoundError, match=r"emulator-events\.jsonl"):
        score(builtin_profile("paper-dynamic"), tmp_path, vehicles=1, duration=1000.0)


def test_moving_targets_are_matched_where_the_emulator_saw_them(tmp_path: Path) -> None:
    profile = builtin_profile("paper-dynamic")
    start = np.array([profile.targets[0].north, profile.targets[0].east])
    moved = start + 480.0  # 240 s of the paper's drift: beyond r2 of where it started
    sensor = profile.sensors[-1].name
    _write(
        tmp_path / EMULATOR_EVENTS,
        [
            {
                "t": 250.0,
                "event": "entered_range",
                "vehicle": 0,
                "target": 0,
                "sensor": sensor,
                "north": moved[0],
                "east": moved[1],
            },
            {
                "t": 250.0,
                "event": "entered_range",
                "vehicle": 1,
                "target": 0,
                "sensor": profile.sensors[0].name,
                "north": moved[0],
                "east": moved[1],
            },
        ],
    )
    _mission(tmp_path / "mission-0.jsonl", [(250.5, moved[0] + 2.0, moved[1] + 1.0)])
    # Vehicle 1 only had the target in its detection sensor: its "confirmation" is not real.
    _mission(tmp_path / "mission-1.jsonl", [(251.0, moved[0], moved[1])])
    result = score(profile, tmp_path, vehicles=2, duration=1000.0)
    ok, unseen = result.confirmations
    assert (ok.vehicle, ok.target, ok.real) == (0, 0, True)
    assert ok.distance < 5.0
    assert (unseen.vehicle, unseen.target, unseen.real) == (1, -1, False)
    assert (result.tnc, result.false_confirmations) == (1, 1)
    assert result.first_confirmation[0] == pytest.approx(240.5)


def test_a_log_of_another_version_is_refused_naming_the_line(tmp_path: Path) -> None:
    log = tmp_path / "mission-0.jsonl"
    _mission(log, [])
    with log.open("a") as f:  # a confirmation logged before ``north`` was renamed
        f.write('{"t":20.0,"event":"confirmation","n":1.0,"east":2.0,"level":1,"found":1}\n')
    with pytest.raises(
        LogFormatError, match="^" + re.escape(f"{log}:2: 'confirmation' record has field 'n'")
    ):
        score(builtin_profile("paper-fixed"), tmp_path, vehicles=1, duration=1000.0)
