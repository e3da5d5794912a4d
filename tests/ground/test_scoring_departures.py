"""Fleet scoring of targets that leave the area: under ``mission.ts_rule: confirmed_or_gone``
each real target counts towards T_S at the earlier of its first confirmation and its departure
(the emulator's ``target_gone`` events), as in the Monte-Carlo engine."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from companion.telemetry import MissionLog, events
from mdm_core.world import Scenario
from mdm_ground.fleet.progress import VehicleView, progress_line
from mdm_ground.fleet.scoring import EMULATOR_EVENTS, FleetResult, score
from mdm_ground.fleet.summary import summary_lines
from mdm_profiles import MissionProfile
from tests.profile_files import profile_with

CONFIRMATION = "confirmation"
T1 = (1500.0, 1500.0)
"""Where the real target T1 is when vehicle 0's confirmation sensor meets it."""


def _profile(rule: str) -> MissionProfile:
    """Two real targets (T1, T2) and a false one (T3) on a free walk."""
    return profile_with(
        "gone-test",
        targets=[
            {"north": 1400.0, "east": 1400.0},
            {"north": 2800.0, "east": 2800.0},
            {"north": 600.0, "east": 2400.0, "false_target": True},
        ],
        target_motion={"boundary": "free", "grid_dt": 10.0},
        mission={"duration": 1000.0, "ts_cap": 5000.0, "ts_rule": rule},
    )


def _mission(path: Path, start: float, confirmations: list[tuple[float, float, float]]) -> None:
    log = MissionLog(path)
    logged: list[tuple[float, events.DurableEvent]] = [
        (start, events.PhaseChange("search", search_start=start))
    ]
    logged += [(t, events.Confirmation(n, e, 1, k)) for k, (t, n, e) in enumerate(confirmations, 1)]
    for t, event in logged:
        log.emit(t, event.NAME, **events.to_fields(event))
    log.close()


def _gone(target: int, left: float, *, false_target: bool = False) -> dict[str, Any]:
    return {
        "t": round(left + 0.05, 1),
        "event": "target_gone",
        "target": target,
        "left_at": left,
        "north": 3000.0,
        "east": 2900.0,
        "false_target": false_target,
    }


def _run(folder: Path, departures: list[dict[str, Any]]) -> None:
    """Vehicle 0 (search from 10 s) confirms T1 at 300.5 s; vehicle 1 searches from 14 s and
    confirms nothing; the emulator logs ``departures``."""
    seen = {"t": 300.0, "event": "entered_range", "vehicle": 0, "target": 0}
    seen |= {"sensor": CONFIRMATION, "north": T1[0], "east": T1[1]}
    lines = [seen, *departures]
    (folder / EMULATOR_EVENTS).write_text("".join(json.dumps(r) + "\n" for r in lines))
    _mission(folder / "mission-0.jsonl", 10.0, [(300.5, T1[0] + 3.0, T1[1])])
    _mission(folder / "mission-1.jsonl", 14.0, [])


def _score(folder: Path, rule: str) -> FleetResult:
    return score(_profile(rule), folder, vehicles=2, duration=1000.0)


def _summary(folder: Path, rule: str) -> list[str]:
    """The summary lines of the run, as of a run that ended normally."""
    return summary_lines(replace(_score(folder, rule), complete=True), folder, wall=1.0)


def test_a_target_that_leaves_unconfirmed_counts_at_its_departure(tmp_path: Path) -> None:
    _run(tmp_path, [_gone(2, 50.0, false_target=True), _gone(1, 150.25), _gone(0, 800.0)])
    result = _score(tmp_path, "confirmed_or_gone")
    assert result.first_confirmation[:2] == [290.5, float("inf")]
    assert result.search_start == 10.0  # the team's: the earlier of the two vehicles'
    assert result.departures == [800.0, 150.25, 50.0]
    # T1 confirmed 290.5 s into the search (before it left at 790 s), T2 gone at 140.25 s;
    # the false T3's departure does not count
    assert (result.ts, result.ts_capped) == (290.5, False)
    assert (result.ts_confirmed, result.ts_gone) == (1, 1)
    assert result.tnc == 1


def test_t_s_is_the_later_of_the_confirmation_and_the_departure(tmp_path: Path) -> None:
    _run(tmp_path, [_gone(1, 610.0)])
    result = _score(tmp_path, "confirmed_or_gone")
    assert (result.ts, result.ts_capped) == (600.0, False)
    assert result.departures == [float("inf"), 610.0, float("inf")]
    as_json = result.as_json()
    assert as_json["departures"] == [None, 610.0, None]
    assert (as_json["ts_confirmed"], as_json["ts_gone"], as_json["ts_rule"]) == (
        1,
        1,
        "confirmed_or_gone",
    )


def test_a_target_gone_before_the_search_counts_at_its_start(tmp_path: Path) -> None:
    _run(tmp_path, [_gone(1, 4.0)])
    result = _score(tmp_path, "confirmed_or_gone")
    assert (result.ts, result.ts_gone) == (290.5, 1)


def test_departures_are_recorded_but_not_counted_under_the_default_rule(tmp_path: Path) -> None:
    _run(tmp_path, [_gone(1, 150.25)])
    result = _score(tmp_path, "confirmed")
    assert result.departures[1] == 150.25
    assert (result.ts, result.ts_capped) == (5000.0, True)
    assert (result.ts_confirmed, result.ts_gone) == (1, 0)


def test_a_run_that_neither_confirms_nor_sees_gone_every_target_is_capped(
    tmp_path: Path,
) -> None:
    _run(tmp_path, [_gone(2, 50.0, false_target=True)])
    result = _score(tmp_path, "confirmed_or_gone")
    assert (result.ts, result.ts_capped) == (5000.0, True)
    assert (result.ts_confirmed, result.ts_gone) == (1, 0)


def test_the_summary_says_how_many_were_confirmed_and_how_many_gone(tmp_path: Path) -> None:
    _run(tmp_path, [_gone(1, 150.25)])
    lines = _summary(tmp_path, "confirmed_or_gone")
    assert "  time to all targets (T_S, confirmed or gone): 290.5 s (1 confirmed, 1 gone)" in lines
    assert "    target T2 left the area at mission time 150.2 s, 140.2 s into the search" in lines


def test_the_summary_of_an_unfinished_run_counts_both(tmp_path: Path) -> None:
    _run(tmp_path, [])
    lines = _summary(tmp_path, "confirmed_or_gone")
    ts = next(line for line in lines if "(T_S" in line)
    assert "not reached: 1 confirmed and 0 gone of 2 real targets in" in ts


def test_a_departure_of_no_profile_target_is_refused_naming_the_file(tmp_path: Path) -> None:
    _run(tmp_path, [_gone(7, 150.0)])
    with pytest.raises(ValueError, match=r"emulator-events\.jsonl: target_gone of target 7"):
        _score(tmp_path, "confirmed_or_gone")


def test_a_virtual_sensor_run_takes_the_departures_of_its_own_world(tmp_path: Path) -> None:
    """No emulator log: the virtual world's tracks (same seed) give the departures, up to the
    last mission time the run logged (600 s here: T2, the nearest to a wall, is gone by then)."""
    profile = _profile("confirmed_or_gone")
    _mission(tmp_path / "mission-0.jsonl", 10.0, [(600.0, 0.0, 0.0)])
    _mission(tmp_path / "mission-1.jsonl", 14.0, [])
    result = score(profile, tmp_path, vehicles=2, duration=1000.0, virtual_seed=9)
    _, tracks = Scenario.from_profile(profile).live_run(9, 2, profile.fleet.start)
    solved = tracks.departures(600.0)[0]
    assert result.departures == solved.tolist()
    assert np.isfinite(solved[1])
    assert result.departures[1] < 600.0
    assert result.ts_gone == 1 + bool(np.isfinite(solved[0]))


def test_the_progress_line_counts_the_targets_gone_where_t_s_counts_them() -> None:
    views = [VehicleView(time=120.0, level=1, phase="search"), VehicleView(time=119.5)]
    assert (
        progress_line(views, 1, 2, gone=1) == "sim t=  120.0 s  confirmed 1/2  gone 1  levels [2C]"
    )
    assert progress_line(views, 1, 2) == "sim t=  120.0 s  confirmed 1/2  levels [2C]"
