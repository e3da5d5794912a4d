"""`companion service`: the unit it writes passes `systemd-analyze verify` (Debian's systemd),
runs `companion run` with the run directory, its bounded log file and the per-boot mission
rule, restarts on a crash but not on bad input, and lets the companion land on a stop; its
command flies against the emulator, and run again (a restart after the end) leaves the ended
mission alone."""

from __future__ import annotations

import configparser
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from companion.service.unit_file import device_unit
from tests.companion.sitl_observer import Observer
from tests.emulator_harness import free_udp_base
from tests.services import missing
from tests.vehicle_venv import BIND_OFFSET, emulator

VENV = Path(sys.executable).parents[1]
COMPANION = VENV / "bin" / "companion"


def _service(*argv: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(COMPANION), "service", *argv], capture_output=True, text=True, timeout=60, check=False
    )


def _unit(path: Path) -> configparser.ConfigParser:
    """The unit's settings (repeated keys: the last; ExecStart's continuation lines joined)."""
    parser = configparser.ConfigParser(strict=False, interpolation=None)
    parser.optionxform = str  # type: ignore[assignment,method-assign]
    parser.read_string(path.read_text().replace("\\\n", " "))
    return parser


def _exec_start(path: Path) -> list[str]:
    return shlex.split(_unit(path)["Service"]["ExecStart"])


def _verify(unit: Path) -> subprocess.CompletedProcess[str]:
    if shutil.which("systemd-analyze") is None:
        missing("no systemd-analyze on PATH (`sudo apt-get install systemd`)")
    return subprocess.run(
        ["systemd-analyze", "verify", str(unit)],
        capture_output=True, text=True, timeout=120, check=False,
    )  # fmt: skip


def test_the_unit_for_a_serial_vehicle_passes_systemd_analyze_verify(tmp_path: Path) -> None:
    unit = tmp_path / "mdm-companion-0.service"
    done = _service(
        "--out", str(unit), "--user", "root", "--profile", "paper-fixed", "--vehicle", "0",
        "--connect", "serial:/dev/serial0:921600", "--system-id", "7", "--mqtt", "10.0.0.2",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "systemctl enable --now mdm-companion-0" in done.stdout
    verified = _verify(unit)
    print(f"systemd-analyze verify {unit.name}: exit {verified.returncode}, "
          f"output {verified.stdout + verified.stderr!r}")  # fmt: skip
    assert verified.returncode == 0, verified.stdout + verified.stderr
    assert verified.stdout + verified.stderr == ""
    settings = _unit(unit)
    service = settings["Service"]
    assert service["Restart"] == "on-failure"
    assert service["RestartPreventExitStatus"].split() == ["2", "130"]
    assert service["KillMode"] == "mixed"  # SIGTERM to the companion alone: it lands
    assert service["TimeoutStopSec"] == "960"  # --land-wait 600 + --flight-log-wait 300 + 60
    assert service["StateDirectory"] == "mdm-search/vehicle-0"
    assert settings["Unit"]["After"] == "dev-serial0.device"  # waits for the device at boot
    assert _exec_start(unit) == [
        str(COMPANION), "run", "--profile", "paper-fixed", "--vehicle", "0",
        "--connect", "serial:/dev/serial0:921600", "--system-id", "7", "--mqtt", "10.0.0.2",
        "--log-dir", "/var/lib/mdm-search/vehicle-0",
        "--log-file", "/var/lib/mdm-search/vehicle-0/companion.log",
        "--new-mission-per-boot", "--no-map",
    ]  # fmt: skip


def test_verify_refuses_a_unit_whose_companion_is_not_there(tmp_path: Path) -> None:
    """The check has teeth: the same unit with its executable gone fails verify."""
    unit = tmp_path / "mdm-companion-0.service"
    assert _service("--out", str(unit), "--user", "root", "--profile", "paper-fixed",
                    "--vehicle", "0").returncode == 0  # fmt: skip
    unit.write_text(unit.read_text().replace(str(COMPANION), str(tmp_path / "gone" / "companion")))
    verified = _verify(unit)
    assert verified.returncode != 0
    assert "gone/companion" in verified.stdout + verified.stderr


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (("--profile", "paper-fixed", "--vehicle", "99"), "vehicle 99: profile has"),
        (("--profile", "no-such-profile", "--vehicle", "0"), "no-such-profile"),
        (("--profile", "paper-fixed", "--vehicle", "0", "--system-id", "300"), "--system-id 300"),
        (
            ("--profile", "paper-fixed", "--vehicle", "0", "--connect", "serial:/dev/ttyS0:fast"),
            "serial",
        ),
        (
            ("--profile", "paper-fixed", "--vehicle", "0", "--log-file", "x.log"),
            "--log-file: set by the unit itself",
        ),
    ],
)
def test_bad_run_options_are_refused_and_no_unit_written(
    tmp_path: Path, argv: tuple[str, ...], said: str
) -> None:
    unit = tmp_path / "u.service"
    done = _service("--out", str(unit), *argv)
    assert done.returncode == 2, done.stdout + done.stderr
    assert said in done.stderr
    assert "Traceback" not in done.stderr
    assert not unit.exists()


def test_a_unit_that_cannot_be_written_is_refused_naming_it(tmp_path: Path) -> None:
    out = tmp_path / "no-such-dir" / "u.service"
    done = _service("--out", str(out), "--profile", "paper-fixed", "--vehicle", "0")
    assert done.returncode == 2
    assert f"cannot write the unit {out}" in done.stderr


def test_relative_files_are_made_absolute_and_specifiers_escaped(tmp_path: Path) -> None:
    profile = tmp_path / "100%.yaml"
    shutil.copy(Path(__file__).parents[2] / "mission_profiles" / "paper-fixed.yaml", profile)
    done = subprocess.run(
        [str(COMPANION), "service", "--out", "-", "--profile", profile.name, "--vehicle", "0"],
        capture_output=True, text=True, timeout=60, check=False, cwd=tmp_path,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert f"--profile {tmp_path}/100%%.yaml" in done.stdout


def test_device_units_are_named_as_systemd_escape_names_them() -> None:
    assert device_unit(Path("/dev/serial0")) == "dev-serial0.device"
    assert device_unit(Path("/dev/serial/by-id/usb-FTDI_FT232R-if00")) == (
        "dev-serial-by\\x2did-usb\\x2dFTDI_FT232R\\x2dif00.device"
    )


def test_the_units_command_flies_and_a_restart_after_the_end_does_nothing(
    tmp_path: Path,
) -> None:
    """The unit's ExecStart, as written, against the emulator: searches, lands, writes its
    bounded companion.log; run again in the same boot (systemd's restart), the ended mission
    stays ended: the vehicle is not taken off again."""
    base = free_udp_base(1, gap=BIND_OFFSET)
    run_dir = tmp_path / "run"
    unit = tmp_path / "u.service"
    assert _service(
        "--out", str(unit), "--log-dir", str(run_dir), "--profile", "paper-fixed",
        "--vehicle", "0", "--base-port", str(base), "--duration", "40", "--max-speedup", "10",
    ).returncode == 0  # fmt: skip
    argv = _exec_start(unit)
    tmp_path.joinpath("emu").mkdir()
    emu = emulator(tmp_path / "emu", base, speedup=10.0)
    observer = Observer(f"udpout:127.0.0.1:{base + BIND_OFFSET}", sysid=1)
    try:
        first = subprocess.run(argv, capture_output=True, text=True, timeout=400, check=False)
        flown = observer.snapshot()
        again = subprocess.run(argv, capture_output=True, text=True, timeout=120, check=False)
        after = observer.snapshot()
    finally:
        observer.close()
        emu.terminate()
        emu.wait(timeout=20)
    assert first.returncode == 0, first.stdout[-2000:] + first.stderr[-3000:]
    assert flown.armed_ever
    assert flown.distance > 100.0, f"flew {flown.distance:.0f} m"
    assert not flown.armed
    assert flown.alt < 1.0
    log_file = (run_dir / "companion.log").read_text()
    assert "mission ended" in first.stdout
    assert "sensor source" in log_file  # the log lines in the run directory too
    assert (run_dir / "boot-id").exists()
    assert "already ended (mission log)" in again.stdout
    assert "Traceback" not in again.stderr
    assert not after.armed
    assert after.distance - flown.distance < 5.0, "flew again after a restart"
    sizes = {p.name: p.stat().st_size for p in sorted(run_dir.iterdir()) if p.is_file()}
    print(f"unit's command: flew {flown.distance:.0f} m, landed; restarted: {again.stdout.strip()!r},"
          f" exit {again.returncode}; run directory bytes {sizes}")  # fmt: skip
