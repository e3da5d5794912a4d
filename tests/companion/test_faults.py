"""Fault tests against the real emulator: companion restart, emulator restart, a silent link,
a pilot taking over. Each asserts what the companion did and reads what the vehicle did from
the emulator's event log."""

from __future__ import annotations

import os
import socket
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from tests_companion_support import Procs, has, records, wait_for

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil


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
        n = len(records(_log(tmp_path))) - 2
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
