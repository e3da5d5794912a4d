"""`companion fleet --resume`: a run whose companion died flies on from its mission log, the
ended vehicles stay ended, and the figures count both parts (README: what a run leaves)."""

from __future__ import annotations

import json
import os
import signal
from pathlib import Path

import pytest

from companion.telemetry import read_log
from mdm_ground.fleet.options import FleetOptions
from mdm_ground.fleet.runner import run_fleet
from tests.fleet_cli import processes_naming, run_fleet_cli, small_profile, start_fleet
from tests.waiting import wait_until

pytestmark = pytest.mark.usefixtures("fleet_processes")


def _search_start(log: Path) -> float | None:
    return read_log(log).search_start


@pytest.mark.timeout(180)
def test_resume_continues_a_killed_companion_and_counts_its_whole_search(tmp_path: Path) -> None:
    profile, out = small_profile(tmp_path), tmp_path / "run"
    first = start_fleet("--profile", profile, "--vehicles", "2", "--duration", "200",
                        "--out", str(out), "--quiet", output=tmp_path / "first.txt")  # fmt: skip
    log1 = out / "mission-1.jsonl"
    wait_until(lambda: _search_start(log1) is not None, 60, "vehicle 1 searching")
    victim = [pid for pid, cmd in processes_naming(str(out)).items() if "--vehicle 1 " in cmd]
    assert len(victim) == 1, victim
    os.kill(victim[0], signal.SIGKILL)
    assert first.wait(120) == 1, (tmp_path / "first.txt").read_text()
    before = json.loads((out / "results.json").read_text())
    assert before["complete"] is False
    assert "killed by signal 9" in before["ends"][1]["how"]
    started = _search_start(log1)

    again = run_fleet_cli(
        "--profile", profile, "--vehicles", "2", "--duration", "200", "--out", str(out)
    )
    assert again.returncode == 2, again.stderr
    assert "add --resume" in again.stderr
    other = run_fleet_cli(
        "--profile", profile, "--vehicles", "2", "--duration", "300", "--out", str(out), "--resume"
    )
    assert other.returncode == 2
    assert f"--resume: {out} was a run with duration 200.0, not 300.0" in other.stderr

    result = run_fleet(
        FleetOptions(profile=profile, out=out, vehicles=2, duration=200.0, resume=True)
    )
    assert result.complete, result.ends
    assert result.ends[0].how == "mission time (earlier run)"
    assert result.ends[0].exit_code is None
    assert result.ends[1].how == "mission time"
    assert result.end_reasons == {0: "mission time", 1: "mission time"}
    assert _search_start(log1) == started, "the resumed vehicle restarted its search clock"
    assert read_log(log1).starts == 2
    assert 200.0 <= result.search_time < 220.0
    run = json.loads((out / "run.json").read_text())
    assert run["resumes"][0]["resumed_vehicles"] == [1]
