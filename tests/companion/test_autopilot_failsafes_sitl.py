"""What the autopilot does by itself when the companion cannot, on stock ArduCopter and PX4
SITL holding only the safety net the companion wrote before arming (``failsafe.safety_net``:
``set``, the default of a profile with a site): the companion's link silenced while the
companion lives, the pack running low, the fence crossed. Each test times, on the autopilot's
second link, the switch to RTL from its cause, and sees the vehicle land and disarm (the
measured rows of docs/companion.md, "What the autopilot does when the companion cannot"; the
companion killed: test_kill_failsafe_sitl.py).

The companion talks to the vehicle through a relay (tests/lying_relay.py) that tells no lies
here: silenced, it is the lost radio; passing only the companion's HEARTBEAT, the companion
still counts as present (no companion-loss failsafe) while its setpoints and commands stop,
and the observer's link flies the vehicle over the fence."""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import yaml

from companion.fence_from_profile import fence_for, profile_frame
from mdm_ground.fleet.sitl_team import px4_param_set
from mdm_profiles import load_profile
from tests import sitl
from tests.companion.sitl_observer import Observer, Trace
from tests.companion.test_sitl_flights import AUTOPILOTS, ON_GROUND, Autopilot, Companion
from tests.emulator_harness import free_udp_base
from tests.lying_relay import LyingRelay
from tests.profile_files import blind_field_search
from tests.waiting import wait_until

HOME = "47.405893,8.663214,440.0"  # inside the Duebendorf fence, its north-east corner
LAYER = 30.0
PUSH_SPEED = 8.0
"""m/s the observer flies the vehicle towards the nearest fence edge (under ArduCopter's stock
WPNAV_SPEED 10 m/s)."""
ARDUCOPTER_PACK_MAH = 1200
"""About 150 vehicle s of hover: 10 % left (BATT_LOW_MAH 120) a minute after take-off."""
PX4_DRAIN_S = 60.0
"""PX4 SIH's SIM_BAT_DRAIN for the battery test: the pack empties in 60 vehicle s armed..."""
PX4_MIN_PCT = 8.0
"""... down to SIM_BAT_MIN_PCT: under BAT_CRIT_THR (10 %, Return), above BAT_EMERGEN_THR
(5 %, Land)."""
REACT_S = 10.0
"""Vehicle s an autopilot may take beyond its own timer to switch to RTL: PX4 holds 5 s
before a failsafe's action (COM_FAIL_ACT_T, stock, kept), ArduCopter waits BATT_LOW_TIMER
(10 s) of low battery, and the observer hears positions and modes at 10 vehicle Hz."""
LOSS_TIMER = {"arducopter": "FS_GCS_TIMEOUT", "px4": "COM_OF_LOSS_T"}
"""The companion-loss time the safety net writes (vehicle s)."""


@dataclass
class Flight:
    """One SITL vehicle flying the field search through a relay, seen by an observer."""

    ap: Autopilot
    inst: sitl.SitlInstance
    relay: LyingRelay
    obs: Observer
    comp: Companion

    def context(self) -> str:
        t = self.obs.snapshot()
        return (
            f"observer: modes {t.modes} alt {t.alt:.1f} battery {t.battery}% armed {t.armed} "
            f"texts {t.texts[-6:]}\ncompanion:\n{self.comp.output()[-3000:]}"
        )

    def await_search(self) -> None:
        self.obs.await_state(
            lambda t: t.armed and t.mode == self.ap.guided_custom and t.alt >= LAYER - 2.0,
            300.0,
            "searching at the layer",
            context=self.context,
        )

    def rtl(self, timeout: float) -> tuple[float, float]:
        """Wait for the autopilot's RTL; when the observer first saw it (wall, vehicle s)."""
        rtl = self.ap.rtl_custom
        wait_until(lambda: rtl in self.obs.snapshot().modes, timeout, "RTL", context=self.context)
        t = self.obs.snapshot()
        first = t.modes.index(rtl)
        return t.mode_stamps[first], t.mode_boots[first]

    def await_landed(self) -> None:
        wait_until(
            lambda: (t := self.obs.snapshot()).landed_state == ON_GROUND and not t.armed,
            300.0,
            "landed and disarmed",
            context=self.context,
        )


def _profile(path: Path, vehicles: int, *, battery_min: float | None = None) -> Path:
    """field-duebendorf at one 30 m layer, virtual sensors that find nothing for minutes;
    ``battery_min`` (with no reserve rule) where the companion's own battery end must stay
    out of the way of the autopilot's."""
    p = blind_field_search(f"failsafes-sitl-{os.getpid()}", vehicles, 900.0)
    p["fleet"]["altitude"] = LAYER
    if battery_min is not None:
        p["site"]["battery_min"] = battery_min
        p["site"]["battery_reserve"] = None
    path.write_text(yaml.safe_dump(p, sort_keys=False))
    return path


@contextmanager
def _flight(
    ap: Autopilot,
    sitl_start: Callable[..., sitl.SitlInstance],
    out: Path,
    *,
    battery_min: float | None = None,
) -> Iterator[Flight]:
    home = f"{HOME},0" if ap.kind == "arducopter" else HOME
    small = battery_min is not None and ap.kind == "arducopter"
    pack = {"battery_mah": ARDUCOPTER_PACK_MAH} if small else {}
    inst = sitl_start(ap.kind, speedup=ap.speedup, home=home, **pack)
    if battery_min is not None and ap.kind == "px4":
        folder = sitl.sitl_dir("px4")
        assert folder is not None
        px4_param_set(folder, inst.index, inst.workdir, "SIM_BAT_DRAIN", PX4_DRAIN_S)
        px4_param_set(folder, inst.index, inst.workdir, "SIM_BAT_MIN_PCT", PX4_MIN_PCT)
    port = free_udp_base(1)
    if ap.kind == "arducopter":
        tcp = int(inst.companion_url.rsplit(":", 1)[1])
        relay = LyingRelay(port, sysid=inst.sysid, vehicle=("127.0.0.1", tcp), kinds=())
        wait_until(relay.connected, 60, "the relay connected to ArduCopter's TCP port")
    else:  # PX4 sends its offboard link to 14540 + index: the relay takes that port
        relay = LyingRelay(port, sysid=inst.sysid, vehicle=14540 + inst.index, kinds=())
        relay.start()
    profile = _profile(out / "profile.yaml", inst.index + 1, battery_min=battery_min)
    obs = Observer(inst.observer_url, inst.sysid)
    comp = Companion(out, profile, inst.index, f"udpin:0.0.0.0:{port}", "pymavlink", 900.0)
    try:
        yield Flight(ap, inst, relay, obs, comp)
    finally:
        obs.push(None)
        comp.kill()
        obs.close()
        relay.stop()


def _texts(t: Trace, *words: str) -> list[str]:
    return [x for x in t.texts if any(w in x.lower() for w in words)]


@pytest.mark.timeout(300)
@pytest.mark.parametrize("ap", AUTOPILOTS)
def test_a_lost_link_with_the_companion_alive_turns_the_vehicle_home(
    ap: Autopilot, sitl_start: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    """The radio goes: nothing passes either way while the companion runs on. ArduCopter's
    GCS failsafe (the companion's HEARTBEAT, FS_GCS_TIMEOUT) and PX4's offboard loss
    (COM_OF_LOSS_T, COM_OBL_RC_ACT) return the vehicle."""
    with _flight(ap, sitl_start, tmp_path) as f:
        f.await_search()
        loss_s = f.obs.read_param(LOSS_TIMER[ap.kind])
        f.relay.silent = True
        cut, cut_boot = time.monotonic(), f.obs.snapshot().boot_s
        at, at_boot = f.rtl(60.0)
        alive = f.comp.process.poll() is None
        f.await_landed()
        t = f.obs.snapshot()
    print(
        f"\n{ap.kind}: link silenced -> RTL {at - cut:.1f} wall s / {at_boot - cut_boot:.1f} "
        f"vehicle s; companion alive then: {alive}; landed, disarmed; texts "
        f"{_texts(t, 'failsafe', 'offboard')}"
    )
    assert alive, "the companion ended before the RTL: not a lost link alone"
    assert 0.0 < at_boot - cut_boot <= loss_s + REACT_S, (loss_s, at_boot - cut_boot)


@pytest.mark.timeout(300)
@pytest.mark.parametrize("ap", AUTOPILOTS)
def test_a_crossed_fence_turns_the_vehicle_home(
    ap: Autopilot, sitl_start: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    """The companion's setpoints and commands stop (its HEARTBEAT still passes: no
    companion-loss failsafe) and the observer's link flies the vehicle out over the nearest
    edge of the fence the companion uploaded. ArduCopter's FENCE_ACTION 1 and PX4's GF_ACTION
    3 return it; the time is counted from the first position outside the polygon."""
    with _flight(ap, sitl_start, tmp_path) as f:
        f.await_search()
        load = load_profile(str(tmp_path / "profile.yaml"))
        fence, frame = fence_for(load), profile_frame(load)
        lat, lon = f.obs.snapshot().last_position or (math.nan, math.nan)
        here = np.array(frame.to_local(lat, lon, 0.0)[:2])
        out = np.array(fence.nearest(*here)) - here
        push = out / np.hypot(*out) * PUSH_SPEED
        f.obs.push((float(push[0]), float(push[1]), 0.0))  # before the companion's stop
        f.relay.companion_types = frozenset({"HEARTBEAT"})
        pushed = time.monotonic()
        at, at_boot = f.rtl(120.0)
        f.obs.push(None)
        f.await_landed()
        t = f.obs.snapshot()
    rows = [
        (stamp, boot, np.array(frame.to_local(la, lo, 0.0)[:2]))
        for (la, lo, _, _), stamp, boot in zip(t.track, t.stamps, t.boots, strict=True)
        if stamp >= pushed
    ]
    outside = [(s, b, p) for s, b, p in rows if not fence.contains(p)]
    assert outside, "the vehicle never crossed the fence"
    crossed, crossed_boot, _ = outside[0]
    beyond = max(float(np.hypot(*(fence.clamp(p) - p))) for _, _, p in outside)
    print(
        f"\n{ap.kind}: fence crossed ({fence.distance(*here):.0f} m from the edge at "
        f"{PUSH_SPEED:g} m/s) -> RTL {at - crossed:.1f} wall s / {at_boot - crossed_boot:.1f} "
        f"vehicle s; at most {beyond:.1f} m outside; landed, disarmed; texts "
        f"{_texts(t, 'fence', 'failsafe')}"
    )
    assert not _texts(t, "gcs failsafe", "offboard"), t.texts  # the fence, not a lost link
    # ArduCopter switches within the position sample that first lies outside (its RTL is heard
    # before that sample: -0.1 vehicle s measured)
    assert -1.0 < at_boot - crossed_boot <= REACT_S


@pytest.mark.timeout(300)
@pytest.mark.parametrize("ap", AUTOPILOTS)
def test_a_low_battery_turns_the_vehicle_home(
    ap: Autopilot, sitl_start: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    """A small pack (ArduCopter BATT_CAPACITY 1200 mAh; PX4 SIH drained in 60 vehicle s) and
    a companion whose own battery end cannot act (site.battery_min 0, no reserve rule):
    ArduCopter's BATT_FS_LOW_ACT 2 below BATT_LOW_MAH and PX4's COM_LOW_BAT_ACT 3 below
    BAT_CRIT_THR return the vehicle; timed from the first SYS_STATUS at or under 10 %."""
    with _flight(ap, sitl_start, tmp_path, battery_min=0.0) as f:
        f.await_search()
        low = wait_until(
            f.obs.snapshot,
            120.0,
            "the battery at 10 %",
            until=lambda t: 0 <= t.battery <= 10,
            context=f.context,
        )
        crossed, crossed_boot = time.monotonic(), low.boot_s
        at, at_boot = f.rtl(60.0)
        f.await_landed()
        t = f.obs.snapshot()
    at_rtl = t.mode_battery[t.modes.index(ap.rtl_custom)]
    print(
        f"\n{ap.kind}: battery 10 % -> RTL {at - crossed:.1f} wall s / "
        f"{at_boot - crossed_boot:.1f} vehicle s; {at_rtl} % at the RTL, {t.battery} % landed; "
        f"texts {_texts(t, 'battery', 'failsafe')}"
    )
    assert not _texts(t, "gcs failsafe", "offboard"), t.texts
    assert 0.0 <= at_boot - crossed_boot <= REACT_S
