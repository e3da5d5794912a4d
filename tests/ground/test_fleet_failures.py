"""A fleet run that went wrong says so: a non-zero exit status, a per-process table with the
first error and the log, and results.json marked incomplete."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from mdm_ground.fleet.options import FleetOptions
from mdm_ground.fleet.runner import run_fleet
from mdm_ground.fleet.summary import exit_status
from tests.fleet_cli import run_fleet_cli, small_profile

pytestmark = pytest.mark.usefixtures("fleet_processes")


@pytest.mark.timeout(120)
def test_vehicles_that_never_climb_fail_the_run(tmp_path: Path) -> None:
    out = tmp_path / "run"
    done = run_fleet_cli(
        "--profile", small_profile(tmp_path, tau=1e9), "--duration", "300", "--out", str(out)
    )
    assert done.returncode == 1, done.stdout + done.stderr
    assert "NOT COMPLETE (3 process(es) did not end normally)" in done.stdout
    for i in range(3):
        how = "climb timeout; RTL accepted; not waiting for the landing, exit code 1"
        log = f"{re.escape(str(out))}/companion-{i}.log"
        row = re.compile(rf"vehicle {i} +{re.escape(how)} +- +{log}")
        assert row.search(done.stdout), done.stdout
    result = json.loads((out / "results.json").read_text())
    assert result["complete"] is False
    assert result["stopped_by"] is None
    assert result["end_reasons"] == {
        "0": "climb timeout",
        "1": "climb timeout",
        "2": "climb timeout",
    }


@pytest.mark.timeout(120)
def test_an_emulator_that_exits_fails_the_run_with_its_error(tmp_path: Path) -> None:
    out = tmp_path / "run"
    result = run_fleet(
        FleetOptions(profile=small_profile(tmp_path), out=out, persona="nosuch", duration=300.0)
    )
    assert exit_status(result) == 1
    assert not result.complete
    assert result.stopped_by == "the emulator's exit"
    emulator = result.ends[-1]
    assert emulator.name == "emulator"
    assert emulator.how.startswith("exited on its own before the companions ended, exit code")
    assert emulator.exit_code not in (None, 0)
    assert emulator.error is not None
    assert "unknown persona 'nosuch'" in emulator.error
    for end in result.ends[:-1]:
        assert end.how.startswith("no end in its mission log"), end
        assert not end.ok
    assert json.loads((out / "results.json").read_text())["complete"] is False


@pytest.mark.timeout(120)
def test_a_complete_run_exits_0_and_json_is_all_of_stdout(tmp_path: Path) -> None:
    out = tmp_path / "run"
    done = run_fleet_cli("--profile", small_profile(tmp_path), "--vehicles", "2",
                         "--duration", "60", "--out", str(out), "--json")  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    printed = json.loads(done.stdout)
    assert printed["complete"] is True
    assert printed["end_reasons"] == {"0": "mission time", "1": "mission time"}
    assert "fleet: UDP ports: companions" in done.stderr


@pytest.mark.timeout(120)
def test_companions_that_exit_with_an_error_show_it_in_the_table(tmp_path: Path) -> None:
    out = tmp_path / "run"
    missing = tmp_path / "no-such-password-file"
    result = run_fleet(FleetOptions(
        profile=small_profile(tmp_path), out=out, vehicles=2, duration=60.0,
        mqtt_args=("--mqtt", "127.0.0.1:1883", "--mqtt-username", "u",
                   "--mqtt-password-file", str(missing)),
    ))  # fmt: skip
    assert exit_status(result) == 1
    assert not result.complete
    for i, end in enumerate(result.ends[:-1]):
        assert end.how == "no end in its mission log, exit code 2"
        assert end.error == f"companion: mqtt.password_file {missing}: No such file or directory"
        assert end.log == str(out / f"companion-{i}.log")
    assert result.ends[-1].ok, "the emulator itself ran fine"
