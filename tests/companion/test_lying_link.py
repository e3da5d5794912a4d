"""A companion flown through a link that lies (tests/lying_relay.py): broken telemetry from the
vehicle's own address and id, a second component with its own clock, dropped, duplicated,
reordered and delayed datagrams; then positions that stay bad, and a link that dies. Against the
emulator's both personas over both backends; what is asserted: no non-finite or too fast
setpoint ever reaches the vehicle, the search goes on through isolated bad samples, a sustained
loss of valid position brings the failsafe, and each ending's exit status and line."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from companion.telemetry.mission_log import read_records
from tests.emulator_harness import free_udp_base
from tests.lying_relay import KINDS, LyingRelay
from tests.profile_files import write_profile_with
from tests.waiting import wait_until

SPEEDUP = 10.0
SPEED = 20.0
FAILSAFE = {"position_timeout": 1.0, "position_hold": 2.0, "link_wait": 4.0}
"""Short failsafe times (wall s) so each ending comes within seconds."""
BOOT_S = 200.0
"""Wall s allowed until the search (an emulator compiling its kernels on a loaded host)."""
CAUSE_OF = {
    "nan": "non-finite",
    "inf": "non-finite",
    "huge": "position out of range",
    "jump": "moved too fast",
    "latlon": None,  # GLOBAL_POSITION_INT: read only by geo-referenced profiles
    "clock_back": "clock went back",
    "second_component": "other component",
}
"""The telemetry check's cause each corruption must be dropped for."""


@dataclass
class Flight:
    relay: LyingRelay
    companion: subprocess.Popen[bytes]
    out: Path

    def log(self) -> str:
        return (self.out / "companion-0.log").read_text(errors="replace")

    def records(self) -> list[dict[str, Any]]:
        path = self.out / "mission-0.jsonl"
        return read_records(path) if path.exists() else []

    def phase(self) -> str | None:
        phases = [r["phase"] for r in self.records() if r["event"] == "phase"]
        return phases[-1] if phases else None

    def wait_exit(self, timeout: float) -> int:
        try:
            return self.companion.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            pytest.fail(f"companion still running after {timeout:g} s:\n{self.log()[-3000:]}")
        finally:
            self.relay.rate_hz = 0.0  # no lies counted that no companion read

    def exit_record(self) -> dict[str, Any]:
        ends = [r for r in self.records() if r["event"] == "exit"]
        assert len(ends) == 1, f"exit records {ends}\n{self.log()[-3000:]}"
        return ends[0]


def _start(args: list[str], log: Path) -> subprocess.Popen[bytes]:
    with log.open("ab") as f:
        return subprocess.Popen(
            [sys.executable, *args],
            stdout=f,
            stderr=subprocess.STDOUT,
            env=dict(os.environ, PYTHONUNBUFFERED="1"),
        )


def _stop(p: subprocess.Popen[bytes]) -> None:
    if p.poll() is None:
        p.send_signal(signal.SIGTERM)
        try:
            p.wait(timeout=10)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()


@pytest.fixture
def fly(fleet_processes: Path) -> Iterator[Callable[..., Flight]]:
    """Starts an emulator vehicle, the relay and a companion; stops them all after the test
    (``fleet_processes``: the test's folder, none of whose processes may outlive it)."""
    tmp_path = fleet_processes
    procs: list[subprocess.Popen[bytes]] = []
    relays: list[LyingRelay] = []
    profile = write_profile_with(
        tmp_path / "lying.yaml", "lying", failsafe=FAILSAFE, mission={"duration": 600.0}
    )

    def start(
        persona: str,
        backend: str,
        *,
        duration: float = 60.0,
        land_wait: float = 600.0,
        **relay: Any,
    ) -> Flight:
        port = free_udp_base(1)
        r = LyingRelay(port, max_speed=SPEED, **relay).start()
        relays.append(r)
        procs.append(_start(
            ["-m", "sim_vehicle_stub.cli", "--profile", str(profile), "-n", "1", "--persona",
             persona, "--base-port", str(r.vehicle_port), "--bind-port-base", "0",
             "--speedup", str(SPEEDUP), "--seed", "3"], tmp_path / "emulator.log"))  # fmt: skip
        companion = _start(
            ["-m", "companion.cli", "run", "--profile", str(profile), "--vehicle", "0",
             "--connect", f"udpin:0.0.0.0:{port}", "--backend", backend, "--log-dir",
             str(tmp_path), "--duration", str(duration), "--land-wait", str(land_wait),
             "--max-speedup", str(SPEEDUP), "--seed", "5", "--no-map"],
            tmp_path / "companion-0.log")  # fmt: skip
        procs.append(companion)
        return Flight(r, companion, tmp_path)

    try:
        yield start
    finally:
        for p in procs:
            _stop(p)
        for r in relays:
            r.stop()


PAIRS = [
    ("px4", "pymavlink"),
    ("ardupilot", "pymavlink"),
    ("px4", "mavsdk"),
    ("ardupilot", "mavsdk"),
]


@pytest.mark.timeout(400)
@pytest.mark.parametrize(("persona", "backend"), PAIRS)
def test_search_flies_through_lies_and_no_bad_setpoint_leaves(
    fly: Callable[..., Flight], persona: str, backend: str
) -> None:
    f = fly(persona, backend, duration=30.0, kinds=KINDS, rate_hz=10.0, fault_chance=0.1)
    rc = f.wait_exit(BOOT_S + 120)
    stats = f.relay.stats
    assert stats.bad_setpoints == [], stats.bad_setpoints[:5]
    assert stats.setpoints > 100, f"only {stats.setpoints} setpoints seen"
    assert all(stats.injected[k] >= 5 for k in KINDS), stats.injected
    assert set(stats.faults) == {"drop", "duplicate", "reorder", "delay"}, stats.faults
    recs = f.records()
    end = [r for r in recs if r["event"] == "end"]
    assert [r["reason"] for r in end] == ["mission time"], f.log()[-3000:]
    dropped = {r["cause"] for r in recs if r["event"] == "telemetry_dropped"}
    for kind, cause in CAUSE_OF.items():
        assert cause is None or cause in dropped, (kind, cause, dropped)
    assert "vehicle clock went back" not in f.log(), "a lie was taken for a reboot"
    assert rc == 0, f.log()[-3000:]
    exit_record = f.exit_record()
    assert (exit_record["status"], exit_record["cause"]) == (0, "RTL: landed and disarmed")
    search_start = next(r["search_start"] for r in recs if r.get("phase") == "search")
    assert recs[-1]["t"] - search_start < 30.0 + 300.0, "mission time ran away"
    _say_counts(f, persona, backend)


def _say_counts(f: Flight, persona: str, backend: str) -> None:
    """The counts for the issue's closing note (printed with -s)."""
    dropped = {r["cause"]: r["total"] for r in f.records() if r["event"] == "telemetry_dropped"}
    print(
        f"\n{persona}/{backend}: injected {dict(f.relay.stats.injected)}, faults "
        f"{dict(f.relay.stats.faults)}, setpoints checked {f.relay.stats.setpoints}, bad "
        f"{len(f.relay.stats.bad_setpoints)}, dropped {dropped}, exit {f.exit_record()}"
    )


@pytest.mark.timeout(400)
@pytest.mark.parametrize(("persona", "backend"), [("px4", "pymavlink"), ("ardupilot", "mavsdk")])
def test_positions_that_stay_bad_bring_the_failsafe(
    fly: Callable[..., Flight], persona: str, backend: str
) -> None:
    f = fly(persona, backend, duration=3000.0, land_wait=0.0, kinds=())
    wait_until(f.phase, BOOT_S, "the search", until=lambda p: p == "search")
    f.relay.all_bad = True
    rc = f.wait_exit(60)
    recs = f.records()
    pauses = [r for r in recs if r["event"] == "phase" and r.get("by") == "position failsafe"]
    assert pauses, f.log()[-3000:]
    end = [r["reason"] for r in recs if r["event"] == "end"]
    assert len(end) == 1, end
    assert end[0].startswith("failsafe: no valid position for"), end
    assert rc == 1
    cause = f.exit_record()["cause"]
    assert cause.startswith("failsafe (no valid position for"), cause
    assert "RTL accepted" in cause, cause
    assert f.relay.stats.bad_setpoints == []


@pytest.mark.timeout(400)
def test_bad_positions_for_a_moment_pause_then_resume_the_search(
    fly: Callable[..., Flight],
) -> None:
    f = fly("px4", "pymavlink", duration=3000.0, land_wait=0.0, kinds=())
    wait_until(f.phase, BOOT_S, "the search", until=lambda p: p == "search")
    f.relay.all_bad = True
    wait_until(f.phase, 20, "the failsafe's pause", until=lambda p: p == "paused")
    f.relay.all_bad = False
    wait_until(f.phase, 30, "the search again", until=lambda p: p == "search")
    assert not [r for r in f.records() if r["event"] == "end"]


@pytest.mark.timeout(400)
@pytest.mark.parametrize("backend", ["pymavlink", "mavsdk"])
def test_link_dead_in_the_search_ends_non_zero_after_link_wait(
    fly: Callable[..., Flight], backend: str
) -> None:
    f = fly("px4", backend, duration=3000.0, land_wait=600.0, kinds=())
    wait_until(f.phase, BOOT_S, "the search", until=lambda p: p == "search")
    f.relay.silent = True
    died = time.monotonic()
    rc = f.wait_exit(60)
    waited = time.monotonic() - died
    assert rc == 1, f.log()[-3000:]
    cause = f.exit_record()["cause"]
    assert cause.startswith("link lost while armed"), cause
    assert " m from home" in cause or " km from home" in cause, cause
    assert waited >= FAILSAFE["link_wait"], waited
    assert "waiting up to 4 s for it" in f.log()
    assert "still armed 600" not in f.log()


@pytest.mark.timeout(400)
def test_link_dead_in_the_rtl_is_not_a_landing_timeout(fly: Callable[..., Flight]) -> None:
    f = fly("px4", "pymavlink", duration=20.0, land_wait=600.0, kinds=())
    wait_until(f.phase, BOOT_S, "the return", until=lambda p: p == "return")
    f.relay.silent = True
    rc = f.wait_exit(60)
    assert rc == 1, f.log()[-3000:]
    cause = f.exit_record()["cause"]
    assert cause.startswith("link lost while armed"), cause
    assert "RTL under way at" in cause, cause
    assert "still armed 600" not in f.log()


@pytest.mark.timeout(400)
def test_landing_wait_timeout_ends_non_zero(fly: Callable[..., Flight]) -> None:
    """A vehicle still armed after --land-wait: exit 1 with where it was."""
    f = fly("px4", "pymavlink", duration=20.0, land_wait=5.0, kinds=())
    rc = f.wait_exit(BOOT_S + 60)
    assert rc == 1, f.log()[-3000:]
    cause = f.exit_record()["cause"]
    assert cause.startswith("5 vehicle s after RTL, still armed at"), cause


@pytest.mark.timeout(400)
def test_a_vehicle_read_off_its_altitude_layer_is_reported_during_the_flight(
    fly: Callable[..., Flight],
) -> None:
    """The vehicle's own telemetry says it is 15 m below its layer (the relay lowers every
    LOCAL_POSITION_NED's altitude, in steps the telemetry check lets through): the companion
    reports it while still searching (console line, ``altitude_layer`` record), then, as it
    climbs back to what it reads as its layer, reports it back."""
    f = fly("px4", "pymavlink", duration=3000.0, land_wait=0.0, kinds=())
    wait_until(f.phase, BOOT_S, "the search", until=lambda p: p == "search")
    for k in range(1, 7):
        f.relay.alt_offset = -2.5 * k
        time.sleep(0.05)

    def layer_records() -> list[dict[str, Any]]:
        return [r for r in f.records() if r["event"] == "altitude_layer"]

    wait_until(layer_records, 60, "an altitude_layer record", until=lambda rs: len(rs) >= 2)
    outside, back = layer_records()[:2]
    layer = outside["layer"]
    assert outside["state"] == "outside"
    assert outside["altitude"] < layer - outside["tolerance"]
    assert back["state"] == "back"
    assert abs(back["altitude"] - layer) <= back["tolerance"]
    assert f.phase() == "search", "reported during the flight, not after it"
    assert f.companion.poll() is None
    assert (
        f"vehicle 0 outside its altitude layer: {outside['altitude']:.1f} m above home" in f.log()
    )
