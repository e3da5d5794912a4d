"""A second emulator that starts sending to a running fleet's companions: each companion keeps
to its own vehicle and the fleet reports the stray sender in its summary and results.json."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from companion.telemetry import events, read_log
from mdm_ground.fleet.ports import free_port_block
from tests.fleet_cli import small_profile
from tests.waiting import wait_until

pytestmark = pytest.mark.usefixtures("fleet_processes")


def _searching(log: Path) -> bool:
    return any(e.phase == "search" for e in read_log(log).of(events.PhaseChange))


@pytest.mark.timeout(120)
def test_a_stray_emulator_is_ignored_and_reported(tmp_path: Path) -> None:
    profile, out = small_profile(tmp_path), tmp_path / "run"
    base = free_port_block(2).base
    fleet = subprocess.Popen(
        [sys.executable, "-m", "companion.cli", "fleet", "--profile", profile, "--vehicles",
         "2", "--duration", "600", "--base-port", str(base), "--out", str(out), "--quiet"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    stray: subprocess.Popen[bytes] | None = None
    try:
        wait_until(lambda: _searching(out / "mission-1.jsonl"), 60, "vehicle 1 searching")
        stray = subprocess.Popen(
            [sys.executable, "-m", "sim_vehicle_stub.cli", "--profile", profile, "--vehicles",
             "2", "--base-port", str(base), "--bind-port-base", "0", "--speedup", "1"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )  # fmt: skip
        stdout, stderr = fleet.communicate(timeout=90)
    finally:
        if stray is not None:
            stray.terminate()
            stray.wait(10)
        fleet.kill()
    assert fleet.returncode == 0, stdout + stderr
    result = json.loads((out / "results.json").read_text())
    assert result["complete"] is True
    for i in range(2):
        strays = result["ends"][i]["strays"]
        assert len(strays) == 1, result["ends"][i]
        assert strays[0].startswith("127.0.0.1:")
        assert f"stray: vehicle {i} heard another sender with its system id, {strays[0]}" in stdout
