"""A fleet run's results.json says what made it (mdm_provenance's record)."""

from __future__ import annotations

import json
import platform
from pathlib import Path

import pytest

from mdm_provenance import package_version
from tests.fleet_cli import run_fleet_cli, small_profile

pytestmark = pytest.mark.usefixtures("fleet_processes")


@pytest.mark.timeout(180)
def test_results_json_carries_the_provenance_of_the_run(tmp_path: Path) -> None:
    out = tmp_path / "run"
    argv = ["--profile", small_profile(tmp_path), "--duration", "60", "--seed", "6"]
    done = run_fleet_cli(*argv, "--out", str(out), timeout=150)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    record = json.loads((out / "results.json").read_text())["provenance"]
    assert record["seed"] == 6
    assert record["command_line"][-2:] == ["--out", str(out)]
    assert record["package_version"] == package_version()
    assert record["python"] == platform.python_version()
    assert isinstance(record["git_dirty"], bool)
    # The fleet's CPU counts its finished children: the emulator and three companions.
    assert record["cpu_s"] > 1.0
    assert record["wall_s"] > 0
