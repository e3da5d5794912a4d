"""Fault tests against the real emulator: companion restart, emulator restart, a silent link,
a pilot taking over. Each asserts what the companion did and reads what the vehicle did from
the emulator's event log."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

SMALL_PROFILE = """
name: small-test
description: three real targets and a false one in a 3 km square, for fault tests
area: {north: 3000.0, east: 3000.0}
targets:
  - {north: 1500.0, east: 1500.0}
  - {north: 700.0, east: 700.0}
  - {north: 2300.0, east: 2300.0}
  - {north: 600.0, east: 2400.0, false_target: true}
fleet: {vehicles: 2, speed: 20.0, tau: 0.33, altitude: 30.0, altitude_step: 5.0}
sensors:
  - {name: detection, radius: 1000.0}
  - {name: confirmation, radius: 200.0}
policy:
  kind: mdm
  memory_radius: 300.0
  levels:
    - {distribution: LS, step: 600.0}
    - distribution: BS
      step: 1000.0
      index: {gamma: 0.1, index_max: 0.95, index_min: 0.2, kappa: 150.0}
mission: {duration: 600.0, ts_cap: 5000.0}
"""


class Procs:
    """Starts and always stops the processes of one test."""

    def __init__(self, out: Path) -> None:
        self.out = out
        self.procs: list[subprocess.Popen[bytes]] = []

    def _start(self, args: list[str], log: str) -> subprocess.Popen[bytes]:
        with (self.out / log).open("ab") as f:
            p = subprocess.Popen(
                [sys.executable, *args], stdout=f, stderr=subprocess.STDOUT,
                env=dict(os.environ, PYTHONUNBUFFERED="1"),
            )  # fmt: skip
        self.procs.append(p)
        return p

    def emulator(self, profile: str, base_port: int, *, vehicles: int = 1, persona: str = "px4",
                 speedup: float = 20.0, extra: tuple[str, ...] = ()) -> subprocess.Popen[bytes]:  # fmt: skip
        return self._start(
            ["-m", "sim_vehicle_stub.cli", "--profile", profile, "-n", str(vehicles),
             "--persona", persona, "--base-port", str(base_port),
             "--bind-port-base", str(base_port + 100), "--speedup", str(speedup),
             "--seed", "3", "--events", str(self.out / "emulator-events.jsonl"), *extra],
            "emulator.log",
        )  # fmt: skip

    def companion(self, profile: str, vehicle: int, base_port: int, *, backend: str = "pymavlink",
                  duration: float = 600.0, extra: tuple[str, ...] = ()) -> subprocess.Popen[bytes]:  # fmt: skip
        return self._start(
            ["-m", "companion.cli", "run", "--profile", profile, "--vehicle", str(vehicle),
             "--base-port", str(base_port), "--backend", backend, "--log-dir", str(self.out),
             "--duration", str(duration), "--land-wait", "0", "--seed", "5", *extra],
            f"companion-{vehicle}.log",
        )  # fmt: skip

    def stop_all(self) -> None:
        for p in self.procs:
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
        for p in self.procs:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


def records(path: Path) -> list[dict[str, Any]]:
    if not path.exists():
        return []
    out = []
    for line in path.read_text().splitlines():
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return out


def wait_for(check: Callable[[], bool], timeout: float, what: str) -> None:
    """Poll ``check`` until true; fails the test naming ``what`` after ``timeout`` wall s."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if check():
            return
        time.sleep(0.2)
    raise AssertionError(f"timed out after {timeout:.0f} s waiting for {what}")


def has(path: Path, event: str, **fields: Any) -> bool:
    return any(
        r.get("event") == event and all(r.get(k) == v for k, v in fields.items())
        for r in records(path)
    )


@pytest.fixture
def procs(tmp_path: Path) -> Iterator[Procs]:
    p = Procs(tmp_path)
    try:
        yield p
    finally:
        p.stop_all()


@pytest.fixture
def small_profile(tmp_path: Path) -> str:
    path = tmp_path / "small-test.yaml"
    path.write_text(SMALL_PROFILE)
    return str(path)


os.environ.setdefault("MAVLINK20", "1")  # before pymavlink reads it
from pymavlink import mavutil  # noqa: E402


def _log(tmp: Path, i: int = 0) -> Path:
    return tmp / f"mission-{i}.jsonl"


def _searching_after(tmp: Path, n: int) -> bool:
    """True when the last phase record after the first ``n`` records is 'search'."""
    phases = [r["phase"] for r in records(_log(tmp))[n:] if r.get("event") == "phase"]
    return bool(phases) and phases[-1] == "search"


@pytest.mark.timeout(120)
def test_killed_companion_restarts_with_its_memory(
    procs: Procs, small_profile: str, tmp_path: Path
) -> None:
    procs.emulator(small_profile, 34700)
    first = procs.companion(small_profile, 0, 34700, duration=3000)
    wait_for(lambda: has(_log(tmp_path), "confirmation"), 60, "a first confirmation")
    first.kill()  # SIGKILL: no chance to clean up
    first.wait()
    confirmed = [r for r in records(_log(tmp_path)) if r["event"] == "confirmation"]
    procs.companion(small_profile, 0, 34700, duration=3000)
    wait_for(lambda: has(_log(tmp_path), "start", resumed=len(confirmed)), 20, "restart")
    restarted_at = max(
        k for k, r in enumerate(records(_log(tmp_path))) if r.get("event") == "start"
    )
    wait_for(lambda: _searching_after(tmp_path, restarted_at), 30, "search resumed")
    time.sleep(8)  # ~160 sim s more of searching around the same target
    later = [r for r in records(_log(tmp_path))[restarted_at:] if r["event"] == "confirmation"]
    for r in later:
        gaps = [np.hypot(r["north"] - c["north"], r["east"] - c["east"]) for c in confirmed]
        assert min(gaps) > 300.0, f"re-confirmed a remembered target after restart: {r}"


@pytest.mark.timeout(120)
def test_emulator_restart_mid_mission_is_flown_through(
    procs: Procs, small_profile: str, tmp_path: Path
) -> None:
    emu = procs.emulator(small_profile, 34720)
    procs.companion(small_profile, 0, 34720, duration=3000)
    wait_for(lambda: has(_log(tmp_path), "phase", phase="search"), 40, "search")
    emu.kill()
    emu.wait()
    wait_for(lambda: has(_log(tmp_path), "link", state="lost"), 15, "link loss noticed")
    procs.emulator(small_profile, 34720)
    wait_for(lambda: has(_log(tmp_path), "link", state="restored"), 30, "link restored")
    n = len(records(_log(tmp_path)))
    wait_for(lambda: _searching_after(tmp_path, n), 40, "search after re-arming and take-off")
    times = [r["t"] for r in records(_log(tmp_path))]
    assert times == sorted(times), "mission time went backwards across the emulator restart"
    armed = [e for e in records(tmp_path / "emulator-events.jsonl") if e["event"] == "armed"]
    assert len(armed) >= 2, "the restarted vehicle was not armed again"


class _Relay:
    """A UDP hop between vehicle and companion that can fall silent (a real socket, no mock)."""

    def __init__(self, listen: int, companion: int) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", listen))
        self.sock.settimeout(0.2)
        self.companion = ("127.0.0.1", companion)
        self.vehicle: tuple[str, int] | None = None
        self.silent = False
        self.running = True
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while self.running:
            try:
                data, addr = self.sock.recvfrom(65536)
            except TimeoutError:
                continue
            if self.silent:
                continue
            if addr == self.companion:
                if self.vehicle is not None:
                    self.sock.sendto(data, self.vehicle)
            else:
                self.vehicle = addr
                self.sock.sendto(data, self.companion)

    def close(self) -> None:
        self.running = False
        self.thread.join()
        self.sock.close()


@pytest.mark.timeout(120)
def test_five_seconds_of_silence_then_the_mission_resumes(
    procs: Procs, small_profile: str, tmp_path: Path
) -> None:
    relay = _Relay(34740, 34750)
    try:
        procs.emulator(small_profile, 34740)
        procs.companion(small_profile, 0, 34750, duration=3000)
        wait_for(lambda: has(_log(tmp_path), "phase", phase="search"), 40, "search")
        relay.silent = True
        time.sleep(5.0)
        relay.silent = False
        assert has(_log(tmp_path), "link", state="lost")
        wait_for(lambda: has(_log(tmp_path), "link", state="restored"), 20, "link restored")
        # From the restored record on (the search may have resumed, and ticks followed, before
        # this poll saw it).
        n = max(k for k, r in enumerate(records(_log(tmp_path)))
                if r.get("event") == "link" and r.get("state") == "restored")  # fmt: skip
        wait_for(lambda: _searching_after(tmp_path, n), 30, "search resumed")
    finally:
        relay.close()
    causes = {e.get("cause") for e in records(tmp_path / "emulator-events.jsonl")
              if e["event"] == "failsafe"}  # fmt: skip
    assert causes, "the vehicle saw no failsafe while its companion was silent"


@pytest.mark.timeout(120)
def test_pilot_takes_over_and_hands_back_mavsdk_ardupilot(
    procs: Procs, small_profile: str, tmp_path: Path
) -> None:
    procs.emulator(small_profile, 34760, persona="ardupilot")
    procs.companion(small_profile, 0, 34760, backend="mavsdk", duration=3000)
    wait_for(lambda: has(_log(tmp_path), "phase", phase="search"), 40, "search")
    pilot = mavutil.mavlink_connection("udpout:127.0.0.1:34860", source_system=255,
                                       source_component=190)  # fmt: skip
    try:
        pilot.mav.command_long_send(1, 1, 176, 0, 129, 5, 0, 0, 0, 0, 0)  # LOITER
        wait_for(lambda: has(_log(tmp_path), "phase", phase="paused"), 10, "companion pauses")
        time.sleep(3.0)
        modes = [e["mode"] for e in records(tmp_path / "emulator-events.jsonl")
                 if e["event"] == "mode"]  # fmt: skip
        assert modes[-1] == "LOITER", f"companion fought the pilot: modes {modes}"
        pilot.mav.command_long_send(1, 1, 176, 0, 129, 4, 0, 0, 0, 0, 0)  # GUIDED
        n = len(records(_log(tmp_path)))
        wait_for(lambda: _searching_after(tmp_path, n), 20, "search after the hand-back")
    finally:
        pilot.close()


@pytest.mark.timeout(120)
def test_pilot_hold_on_px4_is_not_taken_back(
    procs: Procs, small_profile: str, tmp_path: Path
) -> None:
    """HOLD while setpoints flow is a pilot's choice (a setpoint-loss HOLD is taken back)."""
    procs.emulator(small_profile, 34780, persona="px4")
    procs.companion(small_profile, 0, 34780, duration=3000)
    wait_for(lambda: has(_log(tmp_path), "phase", phase="search"), 40, "search")
    pilot = mavutil.mavlink_connection("udpout:127.0.0.1:34880", source_system=255,
                                       source_component=190)  # fmt: skip
    try:
        pilot.mav.command_long_send(1, 1, 176, 0, 129, 4, 3, 0, 0, 0, 0)  # AUTO.LOITER (HOLD)
        wait_for(lambda: has(_log(tmp_path), "phase", phase="paused"), 10, "companion pauses")
        time.sleep(3.0)
    finally:
        pilot.close()
    modes = [e["mode"] for e in records(tmp_path / "emulator-events.jsonl") if e["event"] == "mode"]
    assert modes[-1] == "HOLD", f"companion fought the pilot: modes {modes}"
    phases = [r["phase"] for r in records(_log(tmp_path)) if r.get("event") == "phase"]
    assert phases[-1] == "paused", phases


@pytest.mark.timeout(120)
def test_fallback_hold_during_the_climb_is_retried_not_ended(
    procs: Procs, small_profile: str, tmp_path: Path
) -> None:
    """A companion that stalls mid-climb (SIGSTOP) gets PX4's setpoint-loss HOLD; it climbs again."""
    procs.emulator(small_profile, 34790, persona="px4", speedup=4.0)
    companion = procs.companion(small_profile, 0, 34790, duration=3000)
    wait_for(lambda: has(_log(tmp_path), "phase", phase="climb"), 60, "climb")
    companion.send_signal(signal.SIGSTOP)
    time.sleep(1.5)  # 6 vehicle s without setpoints: COM_OF_LOSS_T is 1 s
    companion.send_signal(signal.SIGCONT)
    wait_for(lambda: has(_log(tmp_path), "phase", phase="search"), 60, "search after the stall")
    causes = [e.get("cause") for e in records(tmp_path / "emulator-events.jsonl")
              if e["event"] == "failsafe"]  # fmt: skip
    assert causes, "the vehicle saw no failsafe while its companion was stopped"
    phases = [r["phase"] for r in records(_log(tmp_path)) if r.get("event") == "phase"]
    climb = phases.index("climb")
    assert "prepare" in phases[climb:], f"no retry after the fall-back HOLD: {phases}"
    assert not has(_log(tmp_path), "end"), "the mission ended instead of climbing again"
