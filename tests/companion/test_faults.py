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
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from companion.telemetry import events, read_log
from tests.emulator_harness import free_udp_base
from tests.profile_files import sensors, write_profile_with
from tests.waiting import wait_until

pytestmark = pytest.mark.usefixtures("fleet_processes")

BIND_OFFSET = 100
"""The emulator binds vehicle i's port at base + BIND_OFFSET + i (a pilot talks to it there)."""


class Procs:
    """Starts and always stops the processes of one test."""

    def __init__(self, out: Path) -> None:
        self.out = out
        self.procs: list[subprocess.Popen[bytes]] = []

    def _start(self, args: list[str], log: str) -> subprocess.Popen[bytes]:
        with (self.out / log).open("ab") as f:
            p = subprocess.Popen(
                [sys.executable, *args],
                stdout=f,
                stderr=subprocess.STDOUT,
                env=dict(os.environ, PYTHONUNBUFFERED="1"),
            )
        self.procs.append(p)
        return p

    def emulator(
        self,
        profile: str,
        base_port: int,
        *,
        vehicles: int = 1,
        persona: str = "px4",
        speedup: float = 20.0,
        extra: tuple[str, ...] = (),
    ) -> subprocess.Popen[bytes]:
        return self._start(
            ["-m", "sim_vehicle_stub.cli", "--profile", profile, "-n", str(vehicles),
             "--persona", persona, "--base-port", str(base_port),
             "--bind-port-base", str(base_port + BIND_OFFSET), "--speedup", str(speedup),
             "--seed", "3", "--events", str(self.out / "emulator-events.jsonl"), *extra],
            "emulator.log",
        )  # fmt: skip

    def companion(
        self,
        profile: str,
        vehicle: int,
        base_port: int,
        *,
        backend: str = "pymavlink",
        duration: float = 600.0,
        extra: tuple[str, ...] = (),
    ) -> subprocess.Popen[bytes]:
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


def has(tmp: Path, kind: type[events.DurableEvent], **fields: Any) -> bool:
    """Vehicle 0's mission log holds an event of ``kind`` with these field values."""
    logged = read_log(_log(tmp)).of(kind)
    return any(all(getattr(e, k) == v for k, v in fields.items()) for e in logged)


@pytest.fixture
def procs(tmp_path: Path) -> Iterator[Procs]:
    p = Procs(tmp_path)
    try:
        yield p
    finally:
        p.stop_all()


@pytest.fixture
def base() -> int:
    """The emulator's base port, free with the ports it binds (base + BIND_OFFSET)."""
    return free_udp_base(1, gap=BIND_OFFSET)


def _pilot(base: int) -> mavutil.mavfile:
    """A pilot's ground station talking to vehicle 0's own port."""
    return mavutil.mavlink_connection(
        f"udpout:127.0.0.1:{base + BIND_OFFSET}", source_system=255, source_component=190
    )


@pytest.fixture
def small_profile(tmp_path: Path) -> str:
    """Three real targets and a false one in a 3 km square."""
    real = [(1500.0, 1500.0), (700.0, 700.0), (2300.0, 2300.0)]
    targets = [{"north": n, "east": e} for n, e in real]
    targets.append({"north": 600.0, "east": 2400.0, "false_target": True})
    path = write_profile_with(
        tmp_path / "small-test.yaml",
        "small-test",
        targets=targets,
        sensors=sensors(1000.0, 200.0),
        policy={"memory_radius": 300.0},
        mission={"duration": 600.0},
    )
    return str(path)


os.environ.setdefault("MAVLINK20", "1")  # before pymavlink reads it
from pymavlink import mavutil  # noqa: E402


def _log(tmp: Path, i: int = 0) -> Path:
    return tmp / f"mission-{i}.jsonl"


def _searching_after(tmp: Path, n: int) -> bool:
    """True when the last phase change after the first ``n`` durable events is 'search'."""
    after = read_log(_log(tmp)).events[n:]
    phases = [e.event.phase for e in after if isinstance(e.event, events.PhaseChange)]
    return bool(phases) and phases[-1] == "search"


@pytest.mark.timeout(120)
def test_killed_companion_restarts_with_its_memory(
    procs: Procs, small_profile: str, tmp_path: Path, base: int
) -> None:
    procs.emulator(small_profile, base)
    first = procs.companion(small_profile, 0, base, duration=3000)
    wait_until(lambda: has(tmp_path, events.Confirmation), 60, "a first confirmation")
    first.kill()  # SIGKILL: no chance to clean up
    first.wait()
    confirmed = read_log(_log(tmp_path)).of(events.Confirmation)
    # The restart comes after the vehicle's setpoint-loss failsafe (PX4: POSCTL after
    # COM_OF_LOSS_T, 1 s of wall time at any speed-up), as after a real crash. Restarted within
    # that second, the companion could see the failsafe's mode change as a pilot taking over,
    # depending on how fast the machine starts Python.
    wait_until(
        lambda: any(r["event"] == "failsafe" for r in records(tmp_path / "emulator-events.jsonl")),
        15,
        "the setpoint-loss failsafe",
    )
    procs.companion(small_profile, 0, base, duration=3000)
    wait_until(lambda: has(tmp_path, events.Start, resumed=len(confirmed)), 60, "restart")
    logged = read_log(_log(tmp_path)).events
    restarted_at = max(k for k, e in enumerate(logged) if isinstance(e.event, events.Start))
    wait_until(lambda: _searching_after(tmp_path, restarted_at), 30, "search resumed")
    resumed = read_log(_log(tmp_path)).last_time
    wait_until(
        lambda: read_log(_log(tmp_path)).last_time,
        30,
        "160 vehicle s more of searching around the same target",
        until=lambda t: t >= resumed + 160.0,
    )
    after = read_log(_log(tmp_path)).events[restarted_at:]
    later = [e.event for e in after if isinstance(e.event, events.Confirmation)]
    for r in later:
        gaps = [np.hypot(r.north - c.north, r.east - c.east) for c in confirmed]
        assert min(gaps) > 300.0, f"re-confirmed a remembered target after restart: {r}"


@pytest.mark.timeout(120)
def test_emulator_restart_mid_mission_is_flown_through(
    procs: Procs, small_profile: str, tmp_path: Path, base: int
) -> None:
    emu = procs.emulator(small_profile, base)
    procs.companion(small_profile, 0, base, duration=3000)
    wait_until(lambda: has(tmp_path, events.PhaseChange, phase="search"), 90, "search")
    emu.kill()
    emu.wait()
    wait_until(lambda: has(tmp_path, events.LinkState, state="lost"), 15, "link loss noticed")
    procs.emulator(small_profile, base)
    wait_until(lambda: has(tmp_path, events.LinkState, state="restored"), 30, "link restored")
    n = len(read_log(_log(tmp_path)).events)
    wait_until(lambda: _searching_after(tmp_path, n), 40, "search after re-arming and take-off")
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
    procs: Procs, small_profile: str, tmp_path: Path, base: int
) -> None:
    companion_port = free_udp_base(1)
    relay = _Relay(base, companion_port)
    try:
        procs.emulator(small_profile, base)
        procs.companion(small_profile, 0, companion_port, duration=3000)
        wait_until(lambda: has(tmp_path, events.PhaseChange, phase="search"), 90, "search")
        relay.silent = True
        time.sleep(5.0)  # the silence under test
        relay.silent = False
        assert has(tmp_path, events.LinkState, state="lost")
        wait_until(lambda: has(tmp_path, events.LinkState, state="restored"), 40, "link restored")
        # From the restored event on (the search may have resumed before this poll saw it).
        logged = read_log(_log(tmp_path)).events
        n = max(
            k
            for k, e in enumerate(logged)
            if isinstance(e.event, events.LinkState) and e.event.state == "restored"
        )
        wait_until(lambda: _searching_after(tmp_path, n), 30, "search resumed")
    finally:
        relay.close()
    causes = {
        e.get("cause")
        for e in records(tmp_path / "emulator-events.jsonl")
        if e["event"] == "failsafe"
    }
    assert causes, "the vehicle saw no failsafe while its companion was silent"


@pytest.mark.timeout(120)
def test_pilot_takes_over_and_hands_back_mavsdk_ardupilot(
    procs: Procs, small_profile: str, tmp_path: Path, base: int
) -> None:
    procs.emulator(small_profile, base, persona="ardupilot")
    procs.companion(small_profile, 0, base, backend="mavsdk", duration=3000)
    wait_until(lambda: has(tmp_path, events.PhaseChange, phase="search"), 90, "search")
    pilot = _pilot(base)
    try:
        pilot.mav.command_long_send(1, 1, 176, 0, 129, 5, 0, 0, 0, 0, 0)  # LOITER
        wait_until(
            lambda: has(tmp_path, events.PhaseChange, phase="paused"), 10, "companion pauses"
        )
        time.sleep(3.0)  # what is under test: 3 s in which the companion does not take it back
        modes = [
            e["mode"] for e in records(tmp_path / "emulator-events.jsonl") if e["event"] == "mode"
        ]
        assert modes[-1] == "LOITER", f"companion fought the pilot: modes {modes}"
        pilot.mav.command_long_send(1, 1, 176, 0, 129, 4, 0, 0, 0, 0, 0)  # GUIDED
        n = len(read_log(_log(tmp_path)).events)
        wait_until(lambda: _searching_after(tmp_path, n), 40, "search after the hand-back")
    finally:
        pilot.close()


@pytest.mark.timeout(120)
def test_pilot_hold_on_px4_is_not_taken_back(
    procs: Procs, small_profile: str, tmp_path: Path, base: int
) -> None:
    """HOLD while setpoints flow is a pilot's choice (a setpoint-loss HOLD is taken back).
    Flown at 4x, not 20x: the companion tells the two apart by a 0.8 vehicle-s gap in its
    setpoints, 40 ms of wall time at 20x, which a loaded host's descheduling reached (CI
    rehearsal: the pilot's HOLD taken back)."""
    procs.emulator(small_profile, base, persona="px4", speedup=4.0)
    procs.companion(small_profile, 0, base, duration=3000)
    wait_until(lambda: has(tmp_path, events.PhaseChange, phase="search"), 90, "search")
    pilot = _pilot(base)
    try:
        pilot.mav.command_long_send(1, 1, 176, 0, 129, 4, 3, 0, 0, 0, 0)  # AUTO.LOITER (HOLD)
        wait_until(
            lambda: has(tmp_path, events.PhaseChange, phase="paused"), 10, "companion pauses"
        )
        time.sleep(3.0)  # what is under test: 3 s in which the companion does not take it back
    finally:
        pilot.close()
    modes = [e["mode"] for e in records(tmp_path / "emulator-events.jsonl") if e["event"] == "mode"]
    assert modes[-1] == "HOLD", f"companion fought the pilot: modes {modes}"
    phases = [e.phase for e in read_log(_log(tmp_path)).of(events.PhaseChange)]
    assert phases[-1] == "paused", phases


@pytest.mark.timeout(120)
def test_fallback_hold_during_the_climb_is_retried_not_ended(
    procs: Procs, small_profile: str, tmp_path: Path, base: int
) -> None:
    """A companion that stalls mid-climb (SIGSTOP) gets PX4's setpoint-loss HOLD; it climbs again."""
    procs.emulator(small_profile, base, persona="px4", speedup=4.0)
    companion = procs.companion(small_profile, 0, base, duration=3000)
    wait_until(lambda: has(tmp_path, events.PhaseChange, phase="climb"), 60, "climb")
    companion.send_signal(signal.SIGSTOP)
    time.sleep(1.5)  # the stall under test: 6 vehicle s without setpoints (COM_OF_LOSS_T 1 s)
    companion.send_signal(signal.SIGCONT)
    wait_until(
        lambda: has(tmp_path, events.PhaseChange, phase="search"), 60, "search after the stall"
    )
    causes = [
        e.get("cause")
        for e in records(tmp_path / "emulator-events.jsonl")
        if e["event"] == "failsafe"
    ]
    assert causes, "the vehicle saw no failsafe while its companion was stopped"
    phases = [e.phase for e in read_log(_log(tmp_path)).of(events.PhaseChange)]
    climb = phases.index("climb")
    assert "prepare" in phases[climb:], f"no retry after the fall-back HOLD: {phases}"
    assert not has(tmp_path, events.End), "the mission ended instead of climbing again"
