"""`companion run` against stock ArduCopter SITL (ArduPilot's own flight code, nothing pre-set on
the vehicle), with both backends. What the vehicle did is read from a second connection
(SERIAL1, ``Observer``), never from the companion's log; the companion's log and console are
read only for what only they can show (it paused, it says why it waits)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from companion.telemetry.mission_log import read_records
from tests import sitl
from tests.companion.sitl_observer import Observer, Trace

SPEEDUP = 5  # stable on 2 shared cores; the companion's timers are wall time, the vehicle's not
GUIDED, LOITER, RTL = 4, 5, 6  # ArduCopter custom modes
ON_GROUND = 1  # MAV_LANDED_STATE_ON_GROUND


def _profile(path: Path, vehicles: int) -> Path:
    """A 3 km square; as many vehicles as the instance index needs (system id = index + 1)."""
    path.write_text(f"""
name: sitl-small
description: a 3 km square for flights against stock SITL
area: {{north: 3000.0, east: 3000.0}}
targets:
  - {{north: 1500.0, east: 1500.0}}
  - {{north: 2300.0, east: 2300.0}}
fleet: {{vehicles: {vehicles}, speed: 20.0, tau: 0.33, altitude: 30.0, altitude_step: 5.0}}
sensors:
  - {{name: detection, radius: 300.0}}
  - {{name: confirmation, radius: 100.0}}
policy:
  kind: mdm
  levels:
    - {{distribution: LS, step: 600.0}}
    - distribution: BS
      step: 300.0
      index: {{gamma: 0.1, index_max: 0.95, index_min: 0.2, kappa: 150.0}}
mission: {{duration: 600.0, ts_cap: 5000.0}}
""")
    return path


class Companion:
    """One `companion run` process in its own process group; output in ``log``."""

    def __init__(self, out: Path, profile: Path, vehicle: int, url: str, backend: str,
                 duration: float) -> None:  # fmt: skip
        self.out, self.vehicle = out, vehicle
        self.log = out / f"companion-{vehicle}.out"
        with self.log.open("ab") as f:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "companion.cli", "run", "--profile", str(profile),
                 "--vehicle", str(vehicle), "--connect", url, "--backend", backend,
                 "--log-dir", str(out), "--duration", str(duration), "--land-wait", "300"],
                stdout=f, stderr=subprocess.STDOUT, start_new_session=True,
                env=dict(os.environ, PYTHONUNBUFFERED="1"),
            )  # fmt: skip

    def output(self) -> str:
        return self.log.read_text(errors="replace")

    def events(self) -> list[dict[str, Any]]:
        return read_records(self.out / f"mission-{self.vehicle}.jsonl")

    def kill(self) -> None:
        if self.process.poll() is None:
            os.killpg(self.process.pid, signal.SIGKILL)
            self.process.wait()


def _until(
    what: str, predicate: Callable[[], bool], timeout: float, context: Callable[[], str]
) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"{what}: not within {timeout} s\n{context()}")
        time.sleep(0.2)


def _phases(events: list[dict[str, Any]]) -> list[str]:
    return [str(e["phase"]) for e in events if e["event"] == "phase"]


def _figures(name: str, trace: Trace, started: float) -> None:
    print(f"\n{name}: observer trace: distance {trace.distance:.0f} m, max altitude "
          f"{trace.max_alt:.1f} m, max ground speed {trace.max_speed:.1f} m/s, modes {trace.modes}, "
          f"end: armed={trace.armed} landed_state={trace.landed_state}; "
          f"{time.monotonic() - started:.0f} s wall")  # fmt: skip


def test_pymavlink_flies_stock_arducopter_through_takeover_kill_and_restart(
    arducopter: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    """Started before the autopilot (retries), flies a search, a pilot's LOITER pauses it and
    GUIDED resumes it, kill -9 and a restart resume it, one SIGINT brings it home and waits."""
    started = time.monotonic()
    index = sitl.free_index("arducopter")
    profile = _profile(tmp_path / "sitl-small.yaml", vehicles=index + 1)
    url = sitl.companion_url("arducopter", index)
    comp = Companion(tmp_path, profile, index, url, "pymavlink", duration=600.0)
    obs: Observer | None = None
    try:
        _until("a retry line while the autopilot is not up", lambda: "retry 1 in" in comp.output(),
               15.0, comp.output)  # fmt: skip
        assert "Traceback" not in comp.output()
        inst = arducopter(speedup=SPEEDUP, index=index)
        obs = Observer(inst.observer_url, inst.sysid)
        ob = obs

        def context() -> str:
            return f"trace {ob.snapshot()}\ncompanion:\n{comp.output()[-3000:]}"

        _until("armed, GUIDED, >= 20 m, 150 m flown", lambda: (
            (t := ob.snapshot()).armed and t.mode == GUIDED and t.alt >= 20 and t.distance >= 150
        ), 150.0, context)  # fmt: skip
        asked = [line for line in comp.output().splitlines() if "asked system" in line]
        assert any("LOCAL_POSITION_NED" in line for line in asked), comp.output()[-3000:]

        # A pilot takes over: the companion stops commanding and leaves LOITER alone.
        ob.set_mode(LOITER)
        _until("paused after LOITER", lambda: "paused" in _phases(comp.events()), 20.0, context)
        held = time.monotonic()
        while time.monotonic() - held < 10.0 / SPEEDUP:  # 10 vehicle s: nobody takes it back
            assert ob.snapshot().mode == LOITER, context()
            time.sleep(0.1)
        before = ob.snapshot().distance
        ob.set_mode(GUIDED)
        _until("search resumed after GUIDED", lambda: (
            _phases(comp.events())[-1] == "search" and ob.snapshot().distance > before + 100
        ), 40.0, context)  # fmt: skip

        # Killed and restarted: the new process takes the airborne vehicle back to the search.
        comp.kill()
        before = ob.snapshot().distance
        comp = Companion(tmp_path, profile, index, url, "pymavlink", duration=600.0)
        _until("restarted companion searching", lambda: (
            sum(e["event"] == "start" for e in comp.events()) == 2
            and _phases(comp.events())[-1] == "search"
            and ob.snapshot().distance > before + 100
        ), 60.0, context)  # fmt: skip

        # One SIGINT: RTL, and the companion waits for the landing, saying so.
        comp.process.send_signal(signal.SIGINT)
        _until("landed and disarmed", lambda: (
            (t := ob.snapshot()).landed_state == ON_GROUND and not t.armed and RTL in t.modes
        ), 150.0, context)  # fmt: skip
        assert comp.process.wait(timeout=30) == 0, context()
        out = comp.output()
        assert "ending (operator): flying RTL and waiting until it lands and disarms" in out
        assert "mission ended (operator)" in out
        trace = ob.snapshot()
        assert trace.armed_ever
        assert trace.max_alt >= 20.0
        assert trace.distance >= 500.0, context()
        assert "Traceback" not in out
        # The autopilot's own words reached the mission log (arming is announced by it).
        texts = [e["text"] for e in comp.events() if e["event"] == "statustext"]
        assert any("Arming motors" in t for t in texts) or "Arming motors" in out, texts
        _figures("pymavlink", trace, started)
    finally:
        comp.kill()
        if obs is not None:
            obs.close()


def test_mavsdk_flies_stock_arducopter_and_a_signal_during_rtl_waits_for_landing(
    arducopter: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    """MAVSDK on ArduPilot: takeoff before Offboard (it left the ground), a full search, RTL at
    mission time; a SIGINT during the RTL does not cut it short."""
    started = time.monotonic()
    inst = arducopter(speedup=SPEEDUP)
    profile = _profile(tmp_path / "sitl-small.yaml", vehicles=inst.index + 1)
    comp = Companion(tmp_path, profile, inst.index, inst.companion_url, "mavsdk", duration=45.0)
    obs = Observer(inst.observer_url, inst.sysid)

    def context() -> str:
        return f"trace {obs.snapshot()}\ncompanion:\n{comp.output()[-3000:]}"

    try:
        _until("RTL at mission time", lambda: obs.snapshot().mode == RTL, 150.0, context)
        comp.process.send_signal(signal.SIGINT)
        _until("landed and disarmed", lambda: (
            (t := obs.snapshot()).landed_state == ON_GROUND and not t.armed
        ), 150.0, context)  # fmt: skip
        assert comp.process.wait(timeout=30) == 0, context()
        out = comp.output()
        assert "ending (mission time): flying RTL and waiting until it lands and disarms" in out
        assert "mission ended (mission time)" in out
        trace = obs.snapshot()
        assert trace.armed_ever
        assert trace.max_alt >= 20.0
        assert trace.distance >= 500.0, context()
        assert trace.modes[-1] == RTL
        _figures("mavsdk", trace, started)
    finally:
        comp.kill()
        obs.close()
