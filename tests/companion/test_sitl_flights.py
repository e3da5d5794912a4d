"""`companion run` against stock autopilots in SITL (ArduCopter, PX4 SIH: their own flight code,
nothing pre-set on the vehicle), with both backends; the autopilot is a test parameter. What the
vehicle did is read from a second connection (ArduCopter SERIAL1, PX4's GCS link: ``Observer``),
never from the companion's log; the companion's log and console are read only for what only they
can show (it paused, it says why it waits)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from companion.fence_from_profile import fence_for
from companion.link.geo import LocalFrame
from companion.telemetry.mission_log import read_records
from mdm_profiles import load_profile
from tests import sitl
from tests.companion.sitl_observer import Observer, Trace

SPEEDUP = 5  # the field test's; the companion's timers are wall time, the vehicle's not
ON_GROUND = 1  # MAV_LANDED_STATE_ON_GROUND


@dataclass(frozen=True)
class Autopilot:
    """What differs between the autopilots for these tests: modes as DO_SET_MODE parameters
    (p2, p3) and as HEARTBEAT custom modes."""

    kind: sitl.Kind
    pilot_mode: tuple[float, float]
    pilot_custom: int
    guided: tuple[float, float]
    guided_custom: int
    rtl_custom: int
    speedup: float
    """Stable here: at 5x under load ~11 PX4's clock outran the companion's setpoints (gaps of
    0.5 vehicle s and more), and a pilot's HOLD then reads as PX4's own fall-back (by design,
    docs/companion.md) and is taken back; 3x leaves that margin."""


# ArduCopter: LOITER 5, GUIDED 4, RTL 6. PX4: custom = main << 16 | sub << 24; HOLD (4, 3),
# OFFBOARD (6, 0), RTL (4, 5).
ARDUCOPTER = Autopilot("arducopter", (5, 0), 5, (4, 0), 4, 6, speedup=5.0)
PX4 = Autopilot("px4", (4, 3), 4 << 16 | 3 << 24, (6, 0), 6 << 16, 4 << 16 | 5 << 24, speedup=3.0)
AUTOPILOTS = [pytest.param(ARDUCOPTER, id="arducopter"), pytest.param(PX4, id="px4")]


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

    def __init__(self, out: Path, profile: Path | str, vehicle: int, url: str, backend: str,
                 duration: float, extra: tuple[str, ...] = ()) -> None:  # fmt: skip
        self.out, self.vehicle = out, vehicle
        self.log = out / f"companion-{vehicle}.out"
        with self.log.open("ab") as f:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "companion.cli", "run", "--profile", str(profile),
                 "--vehicle", str(vehicle), "--connect", url, "--backend", backend,
                 "--log-dir", str(out), "--duration", str(duration), "--land-wait", "300", *extra],
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


def _trace_context(obs: Observer, comp: Companion) -> Callable[[], str]:
    def context() -> str:
        snap = obs.snapshot()
        snap.track = snap.track[-3:]
        return f"trace {snap}\ncompanion:\n{comp.output()[-3000:]}"

    return context


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


@pytest.mark.parametrize("ap", AUTOPILOTS)
def test_pymavlink_flies_through_takeover_kill_and_restart(
    ap: Autopilot, request: pytest.FixtureRequest, tmp_path: Path
) -> None:
    """Started before the autopilot, flies a search; a pilot's mode pauses it and the guided
    mode resumes it; killed (ArduCopter holds in GUIDED, PX4's offboard-loss failsafe takes
    over) and restarted, it takes the vehicle back to the search; one SIGINT brings it home and
    waits for the landing."""
    start = request.getfixturevalue(ap.kind)
    started = time.monotonic()
    index = sitl.free_index(ap.kind)
    profile = _profile(tmp_path / "sitl-small.yaml", vehicles=index + 1)
    url = sitl.companion_url(ap.kind, index)
    comp = Companion(tmp_path, profile, index, url, "pymavlink", duration=600.0)
    obs: Observer | None = None
    try:
        # Before the autopilot is up: TCP is retried with a line per retry; UDP listens and
        # says whom it heard.
        line = "retry 1 in" if ap.kind == "arducopter" else "heard nothing"
        _until(f"'{line}' before the autopilot starts", lambda: line in comp.output(), 15.0,
               comp.output)  # fmt: skip
        inst = start(speedup=ap.speedup, index=index)
        obs = Observer(inst.observer_url, inst.sysid)
        ob = obs

        def context() -> str:
            return f"trace {ob.snapshot()}\ncompanion:\n{comp.output()[-3000:]}"

        _until("armed, guided, >= 20 m, 150 m flown", lambda: (
            (t := ob.snapshot()).armed and t.mode == ap.guided_custom and t.alt >= 20
            and t.distance >= 150
        ), 150.0, context)  # fmt: skip
        if ap.kind == "arducopter":  # a stock ArduCopter streams no positions until asked
            asked = [s for s in comp.output().splitlines() if "asked system" in s]
            assert any("LOCAL_POSITION_NED" in s for s in asked), comp.output()[-3000:]

        # A pilot takes over: the companion stops commanding and leaves the mode alone.
        ob.set_mode(*ap.pilot_mode)
        _until("paused after the pilot's mode", lambda: "paused" in _phases(comp.events()), 20.0,
               context)  # fmt: skip
        held = time.monotonic()
        while time.monotonic() - held < 10.0 / ap.speedup:  # 10 vehicle s: nobody takes it back
            assert ob.snapshot().mode == ap.pilot_custom, context()
            time.sleep(0.1)
        before = ob.snapshot().distance
        ob.set_mode(*ap.guided)
        _until("search resumed after the hand-back", lambda: (
            _phases(comp.events())[-1] == "search" and ob.snapshot().distance > before + 100
        ), 40.0, context)  # fmt: skip

        # Killed: ArduCopter holds in GUIDED (no companion watch by default); PX4 leaves
        # OFFBOARD on its own (COM_OF_LOSS_T). Restarted, the companion takes it back.
        comp.kill()
        if ap.kind == "px4":
            _until("PX4's offboard-loss failsafe", lambda: ob.snapshot().mode != ap.guided_custom,
                   20.0, context)  # fmt: skip
        else:
            time.sleep(5.0 / ap.speedup)  # past GUID_TIMEOUT (3 vehicle s): stopped, still GUIDED
            assert ob.snapshot().mode == ap.guided_custom, context()
        failsafe_mode = ob.snapshot().mode
        before = ob.snapshot().distance
        comp = Companion(tmp_path, profile, index, url, "pymavlink", duration=600.0)
        _until("restarted companion searching", lambda: (
            sum(e["event"] == "start" for e in comp.events()) == 2
            and _phases(comp.events())[-1] == "search"
            and ob.snapshot().mode == ap.guided_custom
            and ob.snapshot().distance > before + 100
        ), 60.0, context)  # fmt: skip

        # One SIGINT: RTL, and the companion waits for the landing, saying so.
        comp.process.send_signal(signal.SIGINT)
        _until("landed and disarmed after RTL", lambda: (
            (t := ob.snapshot()).landed_state == ON_GROUND and not t.armed
            and ap.rtl_custom in t.modes
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
        print(f"\n{ap.kind}: mode after the companion was killed: {failsafe_mode}")
        _figures(f"{ap.kind} pymavlink", trace, started)
    finally:
        comp.kill()
        if obs is not None:
            obs.close()


@pytest.mark.parametrize("ap", AUTOPILOTS)
def test_mavsdk_flies_a_search_and_a_signal_during_rtl_waits_for_landing(
    ap: Autopilot, request: pytest.FixtureRequest, tmp_path: Path
) -> None:
    """MAVSDK: a full search (on ArduPilot the takeoff comes before Offboard, or the vehicle
    never leaves the ground), RTL at mission time; a SIGINT during the RTL does not cut it short."""
    started = time.monotonic()
    inst = request.getfixturevalue(ap.kind)(speedup=SPEEDUP)
    profile = _profile(tmp_path / "sitl-small.yaml", vehicles=inst.index + 1)
    comp = Companion(tmp_path, profile, inst.index, inst.companion_url, "mavsdk", duration=45.0)
    obs = Observer(inst.observer_url, inst.sysid)

    def context() -> str:
        return f"trace {obs.snapshot()}\ncompanion:\n{comp.output()[-3000:]}"

    try:
        _until("RTL at mission time", lambda: obs.snapshot().mode == ap.rtl_custom, 150.0, context)
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
        assert ap.rtl_custom in trace.modes
        _figures(f"{ap.kind} mavsdk", trace, started)
    finally:
        comp.kill()
        obs.close()


def test_field_profile_on_px4_stays_inside_its_fence_with_virtual_sensors(
    px4: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    """The Duebendorf field profile on PX4 started at the profile's origin (its EKF origin is
    then the search box's corner): virtual sensors (no MDM_SENSOR on a stock PX4), every
    position flown in OFFBOARD after entering the fence stays inside it (a few metres of
    overshoot allowed), RTL, landed."""
    started = time.monotonic()
    profile = load_profile("field-duebendorf")
    origin = profile.origin
    inst = px4(speedup=SPEEDUP, home=f"{origin.lat},{origin.lon},{origin.alt}")
    assert inst.index < profile.fleet.vehicles, "instance index beyond the profile's 4 vehicles"
    comp = Companion(tmp_path, "field-duebendorf", inst.index, inst.companion_url, "pymavlink",
                     duration=90.0, extra=("--sensor-source", "virtual"))  # fmt: skip
    obs = Observer(inst.observer_url, inst.sysid)
    context = _trace_context(obs, comp)
    try:
        _until("RTL at mission time", lambda: obs.snapshot().mode == PX4.rtl_custom, 200.0, context)
        _until("landed and disarmed", lambda: (
            (t := obs.snapshot()).landed_state == ON_GROUND and not t.armed
        ), 150.0, context)  # fmt: skip
        assert comp.process.wait(timeout=30) == 0, context()
        trace = obs.snapshot()
        fence = fence_for(profile)
        frame = LocalFrame(origin.lat, origin.lon, origin.alt)
        local = [
            (frame.to_local(lat, lon, origin.alt)[:2], mode) for lat, lon, _, mode in trace.track
        ]
        offboard = [np.array(p) for p, mode in local if mode == PX4.guided_custom]
        entered = next(i for i, p in enumerate(offboard) if fence.contains(p))
        outside = [fence.clamp(p) - p for p in offboard[entered:] if not fence.contains(p)]
        worst = max((float(np.hypot(*d)) for d in outside), default=0.0)
        assert worst < 15.0, f"{len(outside)} positions outside the fence, worst {worst:.1f} m"
        assert trace.distance >= 500.0, context()
        assert trace.max_alt >= 0.9 * profile.fleet.altitude
        out = comp.output()
        assert "sensor source virtual" in out
        assert "MDM_SENSOR" not in out  # virtual sensors never touch the vehicle's parameters
        print(f"\npx4 field profile: {len(offboard)} OFFBOARD positions, {len(outside)} outside "
              f"the fence after entering it (worst {worst:.1f} m)")  # fmt: skip
        _figures("px4 field-duebendorf", trace, started)
    finally:
        comp.kill()
        obs.close()
