"""`--connect serial:DEVICE:BAUD` end to end with both backends: the companion on one end of a
pseudo-terminal pair, socat bridging the other end to the emulator's UDP (as a UART to a flight
controller), at 57600 and 921600 baud; the vehicle's behaviour read on its own second link. A
cable pull (socat ended: the pty closes and its device disappears, then comes back) and devices
that are missing or busy."""

from __future__ import annotations

import fcntl
import os
import shutil
import subprocess
import sys
import termios
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from companion.link.address import parse_address
from companion.link.serial_device import baud_of, open_serial
from companion.telemetry import events, read_log
from tests.emulator_harness import free_udp_base
from tests.vehicle_venv import BIND_OFFSET, fly
from tests.waiting import wait_until

pytestmark = [
    pytest.mark.usefixtures("fleet_processes"),
    pytest.mark.skipif(
        shutil.which("socat") is None, reason="socat missing (apt-get install socat)"
    ),
]
VENV = Path(sys.executable).parents[1]


def _socat(device: Path, udp_port: int, log: Path) -> subprocess.Popen[bytes]:
    """A pty whose other end is ``device``, bridged to the emulator sending to ``udp_port``."""
    with log.open("ab") as f:
        bridge = subprocess.Popen(
            ["socat", f"pty,raw,echo=0,link={device}",
             f"udp4-listen:{udp_port},bind=127.0.0.1,reuseaddr"],
            stdout=f, stderr=subprocess.STDOUT,
        )  # fmt: skip
    wait_until(device.exists, 10, f"socat's pty {device}")
    return bridge


@pytest.fixture
def bridge(tmp_path: Path) -> Iterator[tuple[Path, int, list[subprocess.Popen[bytes]]]]:
    """(device, the emulator's send port, the socat processes started: ended at teardown)."""
    base = free_udp_base(1, gap=BIND_OFFSET)
    device = tmp_path / "ttyFC"
    procs = [_socat(device, base, tmp_path / "socat.log")]
    yield device, base, procs
    for p in procs:
        p.terminate()
        p.wait(timeout=10)


@pytest.mark.parametrize("baud", [57600, 921600])
@pytest.mark.parametrize("backend", ["pymavlink", "mavsdk"])
def test_a_search_over_a_serial_link_flies_and_lands(
    bridge: tuple[Path, int, list[subprocess.Popen[bytes]]],
    tmp_path: Path,
    backend: str,
    baud: int,
) -> None:
    device, base, _ = bridge
    link = ("--connect", f"serial:{device}:{baud}", "--backend", backend)
    flight = fly(VENV, tmp_path / "run", base=base, link=link, draw_map=False)
    log = (flight.out / "companion-0.log").read_text()
    assert flight.returncode == 0, log[-3000:]
    assert f"{device}:{baud}" in log  # the link as opened (MAVSDK spells it serial://)
    seen = flight.vehicle
    assert seen.armed_ever
    assert seen.distance > 200.0, f"flew {seen.distance:.0f} m"
    assert not seen.armed, "still armed"
    assert seen.alt < 1.0, f"ended {seen.alt:.1f} m up"
    assert "Traceback" not in log
    print(f"serial {backend} {baud}: flew {seen.distance:.0f} m, landed and disarmed")


def _pull_cable(
    device: Path, base: int, procs: list[subprocess.Popen[bytes]], out: Path, gone_s: float
) -> None:
    """Once searching: end socat (the pty closes, the device disappears), wait ``gone_s`` wall s,
    start it again on the same device name."""
    wait_until(
        lambda: (
            (out / "mission-0.jsonl").exists()
            and any(
                isinstance(e.event, events.Level) for e in read_log(out / "mission-0.jsonl").events
            )
        ),
        60,
        "the search under way",
    )
    procs[0].terminate()
    procs[0].wait(timeout=10)
    wait_until(lambda: not device.exists(), 5, "the pty gone")
    time.sleep(gone_s)
    procs.append(_socat(device, base, out / "socat-2.log"))


def test_a_cable_pull_is_a_lost_link_ridden_out_with_pymavlink(
    bridge: tuple[Path, int, list[subprocess.Popen[bytes]]], tmp_path: Path
) -> None:
    device, base, procs = bridge
    out = tmp_path / "run"
    flight = fly(
        VENV, out, base=base, duration=200.0, draw_map=False,
        link=("--connect", f"serial:{device}:921600"),
        during=lambda _: _pull_cable(device, base, procs, out, 4.0),
    )  # fmt: skip
    log = (out / "companion-0.log").read_text()
    assert flight.returncode == 0, log[-3000:]
    states = [e.state for e in read_log(out / "mission-0.jsonl").of(events.LinkState)]
    assert states[:2] == ["lost", "restored"], states
    assert f"serial device {device} gone" in log
    assert "Traceback" not in log
    seen = flight.vehicle
    assert not seen.armed, "still armed"
    assert seen.alt < 1.0, f"ended {seen.alt:.1f} m up"
    print(f"cable pull (pymavlink): {states}; flew {seen.distance:.0f} m, landed and disarmed")


def test_a_cable_pull_with_mavsdk_ends_as_a_lost_udp_link_does(
    bridge: tuple[Path, int, list[subprocess.Popen[bytes]]], tmp_path: Path
) -> None:
    """MAVSDK does not open a serial device again once it went away: the link stays lost and
    the mission ends after the profile's failsafe.link_wait, exit 1, as a UDP link that never
    comes back does; never a crash."""
    device, base, procs = bridge
    out = tmp_path / "run"
    flight = fly(
        VENV, out, base=base, duration=200.0, draw_map=False,
        link=("--connect", f"serial:{device}:921600", "--backend", "mavsdk"),
        during=lambda _: _pull_cable(device, base, procs, out, 4.0),
    )  # fmt: skip
    log = (out / "companion-0.log").read_text()
    assert flight.returncode == 1, log[-3000:]
    assert "mission ended (link lost); exit 1: link lost while armed" in log
    assert "Traceback" not in log
    end = read_log(out / "mission-0.jsonl").end
    assert end is not None
    print(f"cable pull (mavsdk): {log.splitlines()[-1]}")


def _refusal(*argv: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(VENV / "bin" / "companion"), "run", "--profile", "paper-fixed", "--vehicle", "0",
         "--no-tlog", "--no-map", *argv],
        capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip


@pytest.mark.parametrize("backend", ["pymavlink", "mavsdk"])
def test_a_missing_device_is_refused_naming_it(tmp_path: Path, backend: str) -> None:
    device = tmp_path / "ttyUSB9"
    done = _refusal("--connect", f"serial:{device}:57600", "--backend", backend)
    assert done.returncode == 2, done.stdout + done.stderr
    assert f"serial device {device}: does not exist" in done.stderr
    assert "Traceback" not in done.stderr


def test_a_busy_device_is_refused_naming_it(
    bridge: tuple[Path, int, list[subprocess.Popen[bytes]]],
) -> None:
    device, _, _ = bridge
    holder = open_serial(parse_address(f"serial:{device}:57600"))  # as a ground station would
    try:
        done = _refusal("--connect", f"serial:{device}:57600")
    finally:
        os.close(holder)
    assert done.returncode == 2, done.stdout + done.stderr
    assert f"serial device {device}: busy" in done.stderr


def test_a_device_without_permission_is_refused_naming_it(
    bridge: tuple[Path, int, list[subprocess.Popen[bytes]]], tmp_path: Path
) -> None:
    device, _, _ = bridge
    real = device.resolve()
    os.chmod(real, 0o600)
    argv = [str(VENV / "bin" / "python"), "-m", "companion.cli", "run", "--profile",
            "paper-fixed", "--vehicle", "0", "--no-tlog", "--no-map",
            "--log-dir", str(tmp_path), "--connect", f"serial:{device}:57600"]  # fmt: skip
    if os.geteuid() == 0:  # root opens anything: the companion runs as nobody
        if shutil.which("setpriv") is None:
            pytest.skip("running as root without setpriv to drop to another user")
        os.chmod(tmp_path, 0o777)
        argv = ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", *argv]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == 2, done.stdout + done.stderr
    assert f"serial device {device}: no permission" in done.stderr


def test_the_device_is_set_raw_at_the_baud_rate_and_locked(
    bridge: tuple[Path, int, list[subprocess.Popen[bytes]]],
) -> None:
    device, _, _ = bridge
    fd = open_serial(parse_address(f"serial:{device}:921600"))
    try:
        assert baud_of(fd) == 921600
        lflag = termios.tcgetattr(fd)[3]
        assert not lflag & (termios.ICANON | termios.ECHO | termios.ISIG)
        other = os.open(device, os.O_RDWR | os.O_NOCTTY)  # root: past TIOCEXCL, not the lock
        try:
            with pytest.raises(BlockingIOError):  # a second user is kept out
                fcntl.flock(other, fcntl.LOCK_EX | fcntl.LOCK_NB)
        finally:
            os.close(other)
    finally:
        os.close(fd)
