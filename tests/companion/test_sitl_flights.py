"""`companion run` against stock autopilots in SITL (ArduCopter, PX4 SIH: their own flight code,
nothing pre-set on the vehicle), with both backends; the autopilot is a test parameter. What the
vehicle did is read from a second connection (ArduCopter SERIAL1, PX4's GCS link: ``Observer``),
never from the companion's log; the companion's log and console are read only for what only they
can show (it paused, it says why it waits)."""

from __future__ import annotations

import math
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
from companion.link.local_frame import LocalFrame
from companion.telemetry.mission_log import read_records
from mdm_ground.fleet.sitl_team import companion_link
from mdm_profiles import load_profile
from tests import sitl
from tests.companion.sitl_observer import Observer, Trace
from tests.profile_files import levels, sensors, write_profile_with
from tests.waiting import wait_until

SPEEDUP = 5  # the field test's; the companion's timers are wall time, the vehicle's not
ON_GROUND = 1  # MAV_LANDED_STATE_ON_GROUND
FENCED_HOME = "47.405893,8.663214,440"  # inside the Duebendorf fence, 1.9 km east of its origin


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
    return write_profile_with(
        path,
        "sitl-small",
        targets=[{"north": 1500.0, "east": 1500.0}, {"north": 2300.0, "east": 2300.0}],
        fleet={"vehicles": vehicles},
        sensors=sensors(300.0, 100.0),
        policy={"levels": levels(600.0, 300.0, 150.0)},
        mission={"duration": 600.0},
    )


class Companion:
    """One `companion run` process in its own process group; output in ``log``."""

    def __init__(
        self,
        out: Path,
        profile: Path | str,
        vehicle: int,
        url: str,
        backend: str,
        duration: float,
        extra: tuple[str, ...] = (),
    ) -> None:
        self.out, self.vehicle = out, vehicle
        self.log = out / f"companion-{vehicle}.out"
        with self.log.open("ab") as f:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "companion.cli", "run", "--profile", str(profile),
                 "--vehicle", str(vehicle), "--connect", url, "--backend", backend,
                 "--log-dir", str(out), "--duration", str(duration), "--land-wait", "600", "--flight-log-wait", "0", *extra],
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


def _phases(events: list[dict[str, Any]]) -> list[str]:
    return [str(e["phase"]) for e in events if e["event"] == "phase"]


def _searched(events: list[dict[str, Any]]) -> float:
    """Vehicle seconds since the search began, as far as the mission log shows (ticks every
    10 vehicle s)."""
    begin = next(e["search_start"] for e in events if "search_start" in e)
    return float(events[-1]["t"]) - float(begin)


def _figures(name: str, trace: Trace, started: float) -> None:
    print(
        f"\n{name}: observer trace: distance {trace.distance:.0f} m, max altitude "
        f"{trace.max_alt:.1f} m, max ground speed {trace.max_speed:.1f} m/s, modes {trace.modes}, "
        f"end: armed={trace.armed} landed_state={trace.landed_state}; "
        f"{time.monotonic() - started:.0f} s wall"
    )


@pytest.mark.parametrize("backend", ["pymavlink", "mavsdk"])
@pytest.mark.parametrize("ap", AUTOPILOTS)
def test_flies_through_takeover_kill_and_restart(
    ap: Autopilot, backend: str, sitl_start: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    """Started before the autopilot, flies a search; a pilot's mode pauses it and the guided
    mode resumes it; killed (ArduCopter holds in GUIDED, PX4's offboard-loss failsafe takes
    over) and restarted, it takes the vehicle back to the search. The end differs by backend,
    so both ways home are flown: pymavlink gets one SIGINT (RTL, it waits for the landing);
    MAVSDK's restarted companion ends at mission time and a SIGINT during that RTL does not cut
    it short. MAVSDK on ArduPilot takes off before its Offboard stream starts (a setpoint
    stream cancels an ArduCopter takeoff)."""
    started = time.monotonic()
    index = sitl.free_index(ap.kind)
    profile = _profile(tmp_path / "sitl-small.yaml", vehicles=index + 1)
    url = companion_link(ap.kind, index)
    comp = Companion(tmp_path, profile, index, url, backend, duration=600.0)
    obs: Observer | None = None
    try:
        if backend == "pymavlink":
            # Before the autopilot is up: TCP is retried with a line per retry; UDP listens
            # and says whom it heard. (MAVSDK waits for the first autopilot in its own way.)
            line = "retry 1 in" if ap.kind == "arducopter" else "heard nothing"
            wait_until(
                lambda: line in comp.output(),
                15.0,
                f"'{line}' before the autopilot starts",
                context=comp.output,
            )
        inst = sitl_start(ap.kind, speedup=ap.speedup, index=index)
        obs = Observer(inst.observer_url, inst.sysid)
        ob = obs

        def context() -> str:
            return f"trace {ob.snapshot()}\ncompanion:\n{comp.output()[-3000:]}"

        wait_until(
            lambda: (
                (t := ob.snapshot()).armed
                and t.mode == ap.guided_custom
                and t.alt >= 20
                and t.distance >= 150
            ),
            150.0,
            "armed, guided, >= 20 m, 150 m flown",
            context=context,
        )
        if ap.kind == "arducopter":  # a stock ArduCopter streams no positions until asked
            asked = [s for s in comp.output().splitlines() if "asked system" in s]
            assert any("LOCAL_POSITION_NED" in s for s in asked), comp.output()[-3000:]

        # A pilot takes over: the companion stops commanding and leaves the mode alone.
        ob.set_mode(*ap.pilot_mode)
        wait_until(
            lambda: "paused" in _phases(comp.events()),
            20.0,
            "paused after the pilot's mode",
            context=context,
        )
        # The observer's link hears the autopilot's next HEARTBEAT up to a second after the
        # companion's did (CI at cb9ff3b: the companion paused on HOLD, the observer still
        # showed OFFBOARD); from then on the pilot's mode must hold.
        wait_until(
            lambda: ob.snapshot().mode == ap.pilot_custom,
            5.0,
            "the observer sees the pilot's mode",
            context=context,
        )
        ob.hold(
            10.0,
            "nobody takes the pilot's mode back",
            lambda t: t.mode == ap.pilot_custom,
            context=context,
        )
        before = ob.snapshot().distance
        ob.set_mode(*ap.guided)
        # By the vehicle's clock (CI of 2026-12-02: 40 wall s ran out for PX4 at 3x under
        # three workers' load): 100 m at the profile's 20 m/s is 5 vehicle s; 120 allowed.
        ob.await_state(
            lambda t: _phases(comp.events())[-1] == "search" and t.distance > before + 100,
            120.0,
            "search resumed after the hand-back",
            context=context,
        )

        # Killed: ArduCopter holds in GUIDED (no companion watch by default); PX4 leaves
        # OFFBOARD on its own (COM_OF_LOSS_T). Restarted, the companion takes it back.
        searched = _searched(comp.events())
        comp.kill()
        if ap.kind == "px4":
            wait_until(
                lambda: ob.snapshot().mode != ap.guided_custom,
                20.0,
                "PX4's offboard-loss failsafe",
                context=context,
            )
        else:
            ob.hold(5.0, "past GUID_TIMEOUT (3 vehicle s)")  # stopped, still GUIDED
            assert ob.snapshot().mode == ap.guided_custom, context()
        failsafe_mode = ob.snapshot().mode
        before = ob.snapshot().distance
        ending = "operator" if backend == "pymavlink" else "mission time"
        # Mission time is the vehicle's and a restart resumes it: the MAVSDK run's restarted
        # companion gets what was searched, the restart (< 40 vehicle s) and 40 s more.
        duration = 600.0 if ending == "operator" else searched + 80.0
        comp = Companion(tmp_path, profile, index, url, backend, duration=duration)
        wait_until(
            lambda: (
                sum(e["event"] == "start" for e in comp.events()) == 2
                and _phases(comp.events())[-1] == "search"
                and ob.snapshot().mode == ap.guided_custom
                and ob.snapshot().distance > before + 100
            ),
            60.0,
            "restarted companion searching",
            context=context,
        )

        if ending == "mission time":
            wait_until(
                lambda: ob.snapshot().mode == ap.rtl_custom,
                90.0,
                "RTL at mission time",
                context=context,
            )
        # One SIGINT: RTL (or, during the RTL, nothing cut short); the companion waits for
        # the landing, saying so.
        comp.process.send_signal(signal.SIGINT)
        wait_until(
            lambda: (
                (t := ob.snapshot()).landed_state == ON_GROUND
                and not t.armed
                and ap.rtl_custom in t.modes
            ),
            150.0,
            "landed and disarmed after RTL",
            context=context,
        )
        # The companion draws its run map after the landing (0.7 s alone; a first matplotlib
        # use builds its font cache, 44 s in one CI container under load): a hang guard only.
        assert comp.process.wait(timeout=480) == 0, context()
        out = comp.output()
        assert f"ending ({ending}): flying RTL and waiting until it lands and disarms" in out
        assert f"mission ended ({ending})" in out
        trace = ob.snapshot()
        assert trace.armed_ever
        assert trace.max_alt >= 20.0
        assert trace.distance >= 500.0, context()
        assert "Traceback" not in out
        print(f"\n{ap.kind} {backend}: mode after the companion was killed: {failsafe_mode}")
        _figures(f"{ap.kind} {backend}", trace, started)
    finally:
        comp.kill()
        if obs is not None:
            obs.close()


def test_field_profile_on_px4_keeps_its_own_fence_and_stays_inside(
    px4: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    """The Duebendorf field profile on PX4 booted inside the site fence, 1.9 km from the
    profile's origin (flown in the profile's frame from PX4's origin): virtual sensors (no
    MDM_SENSOR on a stock PX4), every position flown in OFFBOARD stays inside the fence (a few
    metres of overshoot allowed), RTL, landed. The companion uploads the fence once the vehicle
    is inside it (PX4 enforces any fence it holds: GF_ACTION), and the observer's own
    download (MISSION_REQUEST_LIST, mission_type FENCE) finds the profile's polygon. Then a
    ground station sends the landed vehicle up and across the fence: PX4 keeps it inside
    (measured: "Reposition is outside geofence", the reposition refused)."""
    started = time.monotonic()
    profile = load_profile("field-duebendorf")
    origin = profile.origin
    inst = px4(speedup=SPEEDUP, home=FENCED_HOME)
    # the profile's vehicle 0 flown by whichever instance (system id index + 1) was free
    comp = Companion(
        tmp_path,
        "field-duebendorf",
        0,
        inst.companion_url,
        "pymavlink",
        duration=90.0,
        extra=("--sensor-source", "virtual", "--system-id", str(inst.sysid)),
    )
    obs = Observer(inst.observer_url, inst.sysid)
    context = _trace_context(obs, comp)
    try:
        wait_until(
            lambda: obs.snapshot().mode == PX4.rtl_custom,
            200.0,
            "RTL at mission time",
            context=context,
        )
        wait_until(
            lambda: (t := obs.snapshot()).landed_state == ON_GROUND and not t.armed,
            150.0,
            "landed and disarmed",
            context=context,
        )
        # The companion draws its run map after the landing (0.7 s alone; a first matplotlib
        # use builds its font cache, 44 s in one CI container under load): a hang guard only.
        assert comp.process.wait(timeout=480) == 0, context()
        trace = obs.snapshot()
        fence = fence_for(profile)
        frame = LocalFrame(origin.lat, origin.lon, origin.alt)
        local = [
            (frame.to_local(lat, lon, origin.alt)[:2], mode) for lat, lon, _, mode in trace.track
        ]
        offboard = [np.array(p) for p, mode in local if mode == PX4.guided_custom]
        outside = [fence.clamp(p) - p for p in offboard if not fence.contains(p)]
        worst = max((float(np.hypot(*d)) for d in outside), default=0.0)
        assert worst < 15.0, f"{len(outside)} positions outside the fence, worst {worst:.1f} m"
        assert trace.distance >= 500.0, context()
        assert trace.max_alt >= 0.9 * profile.fleet.altitude
        out = comp.output()
        assert "sensor source virtual" in out
        assert "MDM_SENSOR" not in out  # virtual sensors never touch the vehicle's parameters
        own = [
            (e["state"], e.get("read_back")) for e in comp.events() if e["event"] == "vehicle_fence"
        ]
        assert own == [("uploaded", "equal"), ("enabled", None)], own
        stored = obs.read_fence()

        # PX4 acting on its fence: a ground station takes the landed vehicle up again and sends
        # it 400 m north (DO_REPOSITION), across the fence's north edge; PX4 keeps it inside.
        lat, lon, alt = map(float, FENCED_HOME.split(","))
        target = (lat + 400.0 / 111_200.0, lon)
        assert not fence.contains(np.array(frame.to_local(*target, alt)[:2]))
        flown = len(obs.snapshot().track)
        obs.set_mode(*PX4.pilot_mode)  # HOLD: PX4 reported OFFBOARD again once landed
        obs.command(22, *[math.nan] * 7)  # takeoff to MIS_TAKEOFF_ALT (selects TAKEOFF)
        obs.command(400, 1.0)
        wait_until(lambda: obs.snapshot().alt > 2.0, 60.0, "airborne again", context=context)
        obs.command(192, -1.0, 1.0, 0.0, math.nan, *target, alt + 10.0)
        wait_until(
            lambda: any("geofence" in text.lower() for text in obs.snapshot().texts),
            60.0,
            "PX4's geofence action",
            context=context,
        )
        obs.hold(10.0, "10 vehicle s more: it stays put")
        after = obs.snapshot()
        north = [frame.to_local(la, lo, alt)[0] for la, lo, _, _ in after.track[flown:]]
        beyond = [
            float(np.hypot(*(fence.clamp(p) - p)))
            for p in (
                np.array(frame.to_local(la, lo, alt)[:2]) for la, lo, _, _ in after.track[flown:]
            )
        ]
        texts = [t for t in after.texts if "geofence" in t.lower()]
        print(
            f"\npx4 geofence: {texts}, modes {after.modes[-4:]}, {max(north):.0f} m north of "
            f"the origin, at most {max(beyond):.1f} m outside the fence"
        )
        assert max(beyond) < 15.0, context()
    finally:
        comp.kill()
        obs.close()
    assert profile.site is not None
    polygon = [(round(v.lat * 1e7), round(v.lon * 1e7)) for v in profile.site.geofence]
    vertex = 5001  # MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
    assert stored == [(vertex, lat, lon) for lat, lon in polygon], stored
    print(
        f"\npx4 field profile: {len(offboard)} OFFBOARD positions, {len(outside)} outside "
        f"the fence (worst {worst:.1f} m); fence read back on the GCS link: {len(stored)} "
        f"vertices equal"
    )
    _figures("px4 field-duebendorf", trace, started)
