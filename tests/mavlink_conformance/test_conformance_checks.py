"""The conformance check against the real `sim-vehicle` (PX4 over UDP, ArduPilot over TCP), and
against a vehicle that only sends heartbeats, which must fail."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from mavlink_conformance import run_checks
from mavlink_conformance.cli import main as conformance_main
from sim_vehicle_stub.mavlink import dialect

EXPECTED = {
    "heartbeat", "ids", "mode_encoding", "streams", "timestamps_monotonic",
    "cmd_set_message_interval", "cmd_arm_disarm", "cmd_takeoff", "cmd_unknown", "cmd_do_set_mode",
    "home_position", "autopilot_version", "params_list", "params_read", "params_set",
    "mission_count", "ftp_nak", "timesync",
}  # fmt: skip


@contextmanager
def sim_vehicle(*args: str) -> Iterator[None]:
    exe = Path(sys.executable).parent / "sim-vehicle"
    cmd = [str(exe), "--speedup", "5", "--log-level", "WARNING", *args]
    proc = subprocess.Popen(cmd, env={**os.environ, "MAVLINK20": "1"})
    try:
        yield
    finally:
        proc.terminate()
        proc.wait(10)


@pytest.mark.timeout(60)
def test_emulator_px4_over_udp_passes_every_check() -> None:
    with sim_vehicle("-n", "2", "--base-port", "25400", "--bind-port-base", "0"):
        results = run_checks("udpin:127.0.0.1:25401", sysid=2, timeout=5.0)
    assert {r.name for r in results} == EXPECTED
    assert [r.line() for r in results if not r.passed] == []


@pytest.mark.timeout(60)
def test_emulator_ardupilot_over_tcp_passes_via_the_cli(capsys: pytest.CaptureFixture[str]) -> None:
    args = ["-n", "1", "--persona", "ardupilot", "--tcp", "--tcp-base", "25460"]
    with sim_vehicle(*args, "--base-port", "25450", "--bind-port-base", "0"):
        code = conformance_main(["tcp:127.0.0.1:25460", "--timeout", "5"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "18/18 checks passed" in out
    assert "custom_mode 0x0 = STABILIZE" in out


@pytest.mark.timeout(60)
def test_a_vehicle_that_only_sends_heartbeats_fails_and_the_cli_exits_1(
    capsys: pytest.CaptureFixture[str],
) -> None:
    stop = threading.Event()

    def heartbeats() -> None:
        mav = dialect.MAVLink(None, srcSystem=7, srcComponent=1)
        msg = dialect.MAVLink_heartbeat_message(2, 12, 1, 0x3040000, 3, 3)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            while not stop.wait(0.25):
                sock.sendto(msg.pack(mav), ("127.0.0.1", 25480))

    thread = threading.Thread(target=heartbeats, daemon=True)
    thread.start()
    try:
        code = conformance_main(["udpin:127.0.0.1:25480", "--timeout", "1"])
    finally:
        stop.set()
        thread.join(5)
    out = capsys.readouterr().out
    assert code == 1
    assert "PASS  heartbeat" in out
    assert "PASS  mode_encoding" in out
    assert "FAIL  streams" in out
    assert "FAIL  params_list" in out
