"""The conformance check against the real `sim-vehicle` (PX4 over UDP, ArduPilot over TCP), and
against a vehicle that only sends heartbeats, which must fail."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from mavlink_conformance import run_checks
from mavlink_conformance.checks import check_heartbeat, check_mavlink2, check_streams
from mavlink_conformance.cli import main as conformance_main
from mavlink_conformance.session import Session
from sim_vehicle_stub.mavlink import dialect
from tests.emulator_harness import free_udp_base

EXPECTED = {
    "heartbeat",
    "mavlink2",
    "ids",
    "mode_encoding",
    "streams",
    "timestamps_monotonic",
    "cmd_arm_disarm",
    "cmd_takeoff",
    "cmd_unknown",
    "mode_switch",
    "home_position",
    "autopilot_version",
    "params_list",
    "params_read",
    "params_set",
    "mission_count",
    "plan_capabilities",
    "mission",
    "fence",
    "rally",
    "local_frame",
    "ftp_nak",
    "timesync",
}


@contextmanager
def sim_vehicle(*args: str) -> Iterator[subprocess.Popen[bytes]]:
    """The emulator as a process, yielded once it is up (its sockets bound, its TCP servers
    listening: on a loaded machine its start takes longer than a check's first wait)."""
    exe = Path(sys.executable).parent / "sim-vehicle"
    cmd = [str(exe), "--speedup", "5", "--log-level", "INFO", *args]
    proc = subprocess.Popen(cmd, env={**os.environ, "MAVLINK20": "1"}, stderr=subprocess.PIPE)
    up = threading.Event()

    def read_log() -> None:
        assert proc.stderr is not None
        for line in proc.stderr:
            if b"emulator up" in line:
                up.set()

    reader = threading.Thread(target=read_log, daemon=True)
    reader.start()
    try:
        assert up.wait(60), f"sim-vehicle not up within 60 s (exit code {proc.poll()})"
        yield proc
    finally:
        proc.terminate()
        proc.wait(10)


@pytest.mark.timeout(60)
def test_emulator_px4_over_udp_passes_every_check() -> None:
    base = free_udp_base(2)
    with sim_vehicle("-n", "2", "--base-port", str(base), "--bind-port-base", "0"):
        results = run_checks(f"udpin:127.0.0.1:{base + 1}", sysid=2, timeout=5.0)
    assert {r.name for r in results} == EXPECTED
    assert [r.line() for r in results if not r.passed] == []


@pytest.mark.timeout(60)
def test_stream_rates_are_measured_in_vehicle_time_when_the_vehicle_falls_behind() -> None:
    """A vehicle stopped for 1.6 wall s in the middle of the rate window (a loaded machine: the
    emulator drops the lost time rather than race through it) still streams at the asked rate in
    its own time, and the check measures it there: wall time times the TIMESYNC speed-up would
    count 8 of the window's 15 vehicle s that never happened (about 2.3 Hz for 5)."""
    base = free_udp_base(1)
    with sim_vehicle("-n", "1", "--base-port", str(base), "--bind-port-base", "0") as proc:
        session = Session(f"udpin:127.0.0.1:{base}", sysid=None, source_system=250, timeout=5.0)
        try:
            session.send_heartbeat()
            assert check_heartbeat(session).passed
            pause = threading.Timer(1.2, _stop_for, (proc, 1.6))
            pause.start()
            result = check_streams(session)
            pause.join()
        finally:
            session.close()
    assert session.speed == pytest.approx(5.0, rel=0.2)
    assert result.passed, result.detail
    rates = [float(part.split()[1]) for part in result.detail.split(";")[0].split(", ")]
    assert all(abs(rate - 5.0) < 1.0 for rate in rates), result.detail


def _stop_for(proc: subprocess.Popen[bytes], seconds: float) -> None:
    os.kill(proc.pid, signal.SIGSTOP)
    time.sleep(seconds)
    os.kill(proc.pid, signal.SIGCONT)


@pytest.mark.timeout(60)
def test_emulator_ardupilot_over_tcp_passes_via_the_cli(capsys: pytest.CaptureFixture[str]) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        tcp = probe.getsockname()[1]
    args = ["-n", "1", "--persona", "ardupilot", "--tcp", "--tcp-base", str(tcp)]
    with sim_vehicle(*args, "--base-port", str(free_udp_base(1)), "--bind-port-base", "0"):
        code = conformance_main([f"tcp:127.0.0.1:{tcp}", "--timeout", "5"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "23/23 checks passed" in out
    assert "custom_mode 0x0 = STABILIZE" in out


@contextmanager
def heartbeat_only_vehicle(port: int, period: float, *, mavlink1: bool = False) -> Iterator[None]:
    """A 'vehicle' that sends nothing but HEARTBEATs every ``period`` s."""
    stop = threading.Event()

    def heartbeats() -> None:
        mav = dialect.MAVLink(None, srcSystem=7, srcComponent=1)
        if mavlink1:
            mav.WIRE_PROTOCOL_VERSION = "1.0"
        msg = dialect.MAVLink_heartbeat_message(2, 12, 1, 0x3040000, 3, 3)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            while True:
                sock.sendto(msg.pack(mav, force_mavlink1=mavlink1), ("127.0.0.1", port))
                if stop.wait(period):
                    return

    thread = threading.Thread(target=heartbeats, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join(5)


@pytest.mark.timeout(90)
def test_a_vehicle_that_only_sends_heartbeats_fails_and_the_cli_exits_1(
    capsys: pytest.CaptureFixture[str],
) -> None:
    port = free_udp_base(1)
    # Beats at 2 Hz (passes the rate check) so the 1 s wait for the first one cannot miss it.
    with heartbeat_only_vehicle(port, 0.5):
        code = conformance_main([f"udpin:127.0.0.1:{port}", "--timeout", "1"])
    out = capsys.readouterr().out
    assert code == 1
    assert "PASS  heartbeat" in out
    assert "PASS  mavlink2" in out
    assert "PASS  mode_encoding" in out
    assert "FAIL  streams" in out
    assert "FAIL  mode_switch" in out
    assert "FAIL  params_list" in out


@pytest.mark.timeout(90)
def test_slow_heartbeats_and_mavlink1_only_are_named() -> None:
    port = free_udp_base(1)
    session = Session(f"udpin:127.0.0.1:{port}", sysid=None, source_system=250, timeout=3.0)
    try:
        with heartbeat_only_vehicle(port, 2.0, mavlink1=True):
            results = {r.name: r for r in (check_heartbeat(session), check_mavlink2(session))}
    finally:
        session.close()
    assert not results["heartbeat"].passed, results["heartbeat"].detail
    assert "0.50 Hz" in results["heartbeat"].detail  # measured, not rounded up to pass
    assert not results["mavlink2"].passed
    assert "MAVLink 1 only" in results["mavlink2"].detail


@pytest.mark.timeout(60)
def test_a_closed_tcp_link_stops_the_run_at_once_with_a_clear_error() -> None:
    server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    server.bind(("127.0.0.1", 0))
    server.listen(1)
    port = server.getsockname()[1]
    mav = dialect.MAVLink(None, srcSystem=7, srcComponent=1)
    beat = dialect.MAVLink_heartbeat_message(2, 3, 1, 0, 3, 3).pack(mav)

    def serve() -> None:
        conn, _ = server.accept()
        conn.sendall(beat)
        conn.close()  # the autopilot dies

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    started = time.monotonic()
    results = run_checks(f"tcp:127.0.0.1:{port}", timeout=3.0)
    elapsed = time.monotonic() - started
    thread.join(5)
    server.close()
    assert results[-1].name == "link"
    assert not results[-1].passed
    assert "closed it or died" in results[-1].detail
    assert elapsed < 15.0  # stopped, not every check timing out in turn


def _frames(data: bytes) -> Iterator[bytes]:
    """The MAVLink 2 frames of one datagram (the emulator sends several per datagram)."""
    at = 0
    while at + 12 <= len(data) and data[at] == 0xFD:
        end = at + 12 + data[at + 1] + (13 if data[at + 2] & 1 else 0)
        yield data[at:end]
        at = end


def _drop_first(frame: bytes, dropped: list[int]) -> bool:
    """Whether to lose this frame: the first PARAM_VALUE (id 22) of an index ending in 3."""
    index = int.from_bytes(frame[16:18], "little")  # PARAM_VALUE payload bytes 6-7
    if int.from_bytes(frame[7:10], "little") != 22 or index % 10 != 3 or index in dropped:
        return False
    dropped.append(index)
    return True


@contextmanager
def param_dropping_relay(vehicle_port: int, checker_port: int) -> Iterator[list[int]]:
    """A UDP relay that loses the first PARAM_VALUE of every tenth index (3, 13, ...), as a lossy
    link does; it yields the list of indices it dropped."""
    dropped: list[int] = []
    stop = threading.Event()
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", vehicle_port))
    sock.settimeout(0.2)

    def relay() -> None:
        vehicle = None
        while not stop.is_set():
            try:
                data, addr = sock.recvfrom(65536)
            except TimeoutError:
                continue
            if addr[1] == checker_port:
                if vehicle is not None:
                    sock.sendto(data, vehicle)
                continue
            vehicle = addr
            kept = b"".join(f for f in _frames(data) if not _drop_first(f, dropped))
            if kept:
                sock.sendto(kept, ("127.0.0.1", checker_port))

    thread = threading.Thread(target=relay, daemon=True)
    thread.start()
    try:
        yield dropped
    finally:
        stop.set()
        thread.join(5)
        sock.close()


@pytest.mark.timeout(90)
def test_parameters_the_list_stream_lost_are_read_again_by_index() -> None:
    base = free_udp_base(2)
    vehicle_port, checker_port = base, base + 1
    with (
        param_dropping_relay(vehicle_port, checker_port) as dropped,
        sim_vehicle("-n", "1", "--base-port", str(vehicle_port), "--bind-port-base", "0"),
    ):
        results = run_checks(f"udpin:127.0.0.1:{checker_port}", sysid=1, timeout=3.0)
    by_name = {r.name: r for r in results}
    assert len(dropped) >= 2, dropped
    assert by_name["params_list"].passed, by_name["params_list"].detail
    assert f"({len(dropped)} re-read by index)" in by_name["params_list"].detail
