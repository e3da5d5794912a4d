"""`companion fleet` refuses bad input before any process starts: exit 2 and a message naming
the argument, its value and the limit; nothing is written to the run directory."""

from __future__ import annotations

import json
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from companion.cli import main
from mdm_ground.fleet.ports import free_port_block
from mdm_ground.fleet.preflight import RUN_FILE
from mdm_profiles import builtin_profile
from mdm_profiles.loader import write_profile
from mdm_profiles.overrides import apply_overrides
from tests.fleet_cli import small_profile


def _refused(capsys: pytest.CaptureFixture[str], *args: str) -> str:
    code = main(["fleet", "--quiet", *args])
    err = capsys.readouterr().err
    assert code == 2, err
    return err


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["--vehicles", "0"],
            "--vehicles 0: must be 1..12 (profile 'paper-fixed' has 12 vehicles)",
        ),
        (["--vehicles", "-2"], "--vehicles -2: must be 1..12"),
        (["--vehicles", "14"], "--vehicles 14: must be 1..12"),
        (["--vehicles", "500"], "--vehicles 500: must be 1..12"),
        (["--duration", "0"], "--duration 0: must be > 0"),
        (["--duration", "-5"], "--duration -5: must be > 0"),
        (["--speedup", "-1"], "--speedup -1: must be >= 0"),
        (["--land-wait", "-1"], "--land-wait -1: must be >= 0"),
    ],
)
def test_bad_numbers_are_refused_with_the_limit(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, args: list[str], message: str
) -> None:
    out = tmp_path / "run"
    assert message in _refused(capsys, "--out", str(out), *args)
    assert not out.exists(), "a refused run created its directory"


def test_more_vehicles_than_mavlink_has_system_ids_is_refused(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    profile = Path(small_profile(tmp_path))
    profile.write_text(profile.read_text().replace("vehicles: 3", "vehicles: 300"))
    err = _refused(capsys, "--profile", str(profile), "--out", str(tmp_path / "run"))
    assert "--vehicles 300: must be 1..254 (MAVLink system ids stop at 254)" in err


def test_an_out_that_cannot_be_written_is_refused(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    err = _refused(capsys, "--out", str(blocker / "run"))
    assert f"--out {blocker / 'run'}: not writable (Not a directory)" in err


def test_a_used_out_is_refused_unless_resuming_and_resume_needs_a_run(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    used = tmp_path / "used"
    used.mkdir()
    (used / "mission-0.jsonl").write_text('{"t":1,"event":"start"}\n')
    err = _refused(capsys, "--out", str(used))
    assert f"--out {used}: already holds a run (mission-0.jsonl)" in err
    assert "add --resume to continue that run" in err
    assert (used / "mission-0.jsonl").read_text() == '{"t":1,"event":"start"}\n'
    empty = tmp_path / "empty"
    empty.mkdir()
    assert f"--resume: {empty} holds no run to continue" in _refused(
        capsys, "--out", str(empty), "--resume"
    )


def test_a_busy_base_port_is_refused_naming_the_port(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    base = free_port_block(2).base
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", base + 3))  # the emulator's vehicle 1
        err = _refused(
            capsys, "--vehicles", "2", "--base-port", str(base), "--out", str(tmp_path / "run")
        )
    assert f"--base-port {base}: UDP port {base + 3} (the emulator's vehicle 1):" in err
    assert "leave --base-port out for a free block" in err


@pytest.mark.usefixtures("fleet_processes")
def test_a_base_port_another_emulator_sends_to_is_refused(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    base = free_port_block(2).base
    stray = subprocess.Popen(
        [sys.executable, "-m", "sim_vehicle_stub.cli", "--vehicles", "2", "--base-port",
         str(base), "--bind-port-base", "0", "--log-level", "WARNING"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            s.bind(("0.0.0.0", base))
            s.settimeout(30)
            s.recvfrom(2048)  # the stray is up and sending to our port
        err = _refused(
            capsys, "--vehicles", "2", "--base-port", str(base), "--out", str(tmp_path / "run")
        )
    finally:
        stray.terminate()
        stray.wait(10)
    assert f"--base-port {base}: 127.0.0.1:" in err
    assert "another emulator or vehicle is already talking there" in err


def test_resuming_a_run_whose_log_another_version_wrote_is_refused_naming_the_line(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    run = tmp_path / "run"
    run.mkdir()
    asked = {"profile": "paper-fixed", "vehicles": 1, "seed": 1, "duration": 300.0}
    (run / RUN_FILE).write_text(json.dumps(asked))
    log = run / "mission-0.jsonl"
    log.write_text('{"t":900.0,"event":"end","why":"mission time","found":0}\n')
    err = _refused(
        capsys, "--out", str(run), "--resume", "--vehicles", "1", "--seed", "1", "--duration", "300"
    )
    assert f"--resume: {log}:1: 'end' record has field 'why', which End does not know" in err


def test_a_study_only_policy_is_refused_before_any_companion_starts(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """policy.redetection other than 'ignore' is the engine's alone: the fleet says so once,
    rather than starting an emulator and twelve companions that each exit 2."""
    renewing = apply_overrides(builtin_profile("paper-fixed"), ["policy.redetection=renew"])
    path = tmp_path / "renew.yaml"
    write_profile(renewing, path)
    out = tmp_path / "run"
    err = _refused(capsys, "--profile", str(path), "--out", str(out))
    assert "policy.redetection 'renew' reads the detection sensor on the last level" in err
    assert not out.exists()
