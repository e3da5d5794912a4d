"""Ctrl-C on `companion fleet` (SIGINT to its process group, as a terminal sends it): the first
lands every vehicle and writes the summary and results.json; a second stops at once and still
writes them. The companions, in their own process groups, get only what the fleet sends."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from companion.telemetry import events, read_log, read_records
from tests.fleet_cli import processes_naming, small_profile, start_fleet
from tests.waiting import wait_until

pytestmark = pytest.mark.usefixtures("fleet_processes")


def _searching(out: Path, vehicles: int) -> bool:
    for i in range(vehicles):
        phases = [e.phase for e in read_log(out / f"mission-{i}.jsonl").of(events.PhaseChange)]
        if not phases or phases[-1] != "search":
            return False
    return True


def _start_searching(tmp_path: Path) -> tuple[subprocess.Popen[bytes], Path, Path]:
    out, screen = tmp_path / "run", tmp_path / "screen.txt"
    fleet = start_fleet("--profile", small_profile(tmp_path), "--speedup", "50",
                        "--duration", "5000", "--out", str(out), output=screen)  # fmt: skip
    wait_until(lambda: _searching(out, 3), 60, "every vehicle searching")
    return fleet, out, screen


def _results(out: Path) -> dict[str, Any]:
    result: dict[str, Any] = json.loads((out / "results.json").read_text())
    return result


@pytest.mark.timeout(120)
def test_one_sigint_lands_every_vehicle_then_writes_the_summary(tmp_path: Path) -> None:
    fleet, out, screen = _start_searching(tmp_path)
    os.killpg(fleet.pid, signal.SIGINT)
    assert fleet.wait(90) == 130, screen.read_text()
    text = screen.read_text()
    assert "fleet: SIGINT: every vehicle flies its end action" in text
    assert "fleet: every vehicle has landed" in text
    assert "NOT COMPLETE (stopped by SIGINT)" in text
    result = _results(out)
    assert result["complete"] is False
    assert result["stopped_by"] == "SIGINT"
    assert result["end_reasons"] == {"0": "operator", "1": "operator", "2": "operator"}
    for i in range(3):
        assert "second signal" not in (out / f"companion-{i}.log").read_text()
    emulator = read_records(out / "emulator-events.jsonl")
    for i in range(3):
        mine = [
            r["event"] if r["event"] != "mode" else r["mode"]
            for r in emulator
            if r.get("vehicle") == i and r["event"] in ("mode", "armed", "disarmed")
        ]
        # RTL flown to the ground; the PX4 persona, as PX4, then holds once landed and disarmed
        assert mine[-3:] == ["RTL", "disarmed", "HOLD"], f"vehicle {i}: {mine}"
    assert not processes_naming(str(out))


@pytest.mark.timeout(120)
def test_a_second_sigint_stops_at_once_and_still_writes_results(tmp_path: Path) -> None:
    fleet, out, screen = _start_searching(tmp_path)
    os.killpg(fleet.pid, signal.SIGINT)
    wait_until(lambda: "fleet: SIGINT" in screen.read_text(), 20, "the first stop taken")
    os.killpg(fleet.pid, signal.SIGINT)
    assert fleet.wait(30) == 130, screen.read_text()
    assert "fleet: second SIGINT: stopping every process at once" in screen.read_text()
    result = _results(out)
    assert result["complete"] is False
    assert result["stopped_by"] == "SIGINT"
    assert len(result["ends"]) == 4
    assert not processes_naming(str(out))


@pytest.mark.skipif(sys.platform != "linux", reason="PR_SET_PDEATHSIG is Linux only")
@pytest.mark.timeout(120)
def test_a_killed_fleet_leaves_no_process_behind(tmp_path: Path) -> None:
    fleet, out, _ = _start_searching(tmp_path)
    children = set(processes_naming(str(out))) - {fleet.pid}
    assert len(children) == 4, children  # the emulator and three companions
    fleet.kill()  # SIGKILL: the fleet cannot stop its children itself
    fleet.wait(10)
    try:
        wait_until(
            lambda: processes_naming(str(out)),
            30,
            "the fleet's children gone",
            until=lambda left: not left,
        )
    finally:
        for pid in processes_naming(str(out)):
            os.kill(pid, signal.SIGKILL)
