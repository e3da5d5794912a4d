"""``kill -9`` of `companion run` mid-search on stock ArduCopter and PX4 SITL, with each backend:
nothing set on the vehicle by hand, only the safety net the companion wrote before arming
(``failsafe.safety_net: set``). Seen on the autopilot's second link (``Observer``): its
parameters as the safety net needs them, RTL within a few seconds of the kill, landed and
disarmed; and no process the companion started outlives it (MAVSDK runs in-process: its
library dies with the companion; any child would be listed here)."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import pytest

from mdm_profiles import load_profile
from tests import sitl
from tests.companion.sitl_observer import Observer
from tests.companion.test_autopilot_failsafes_sitl import LOSS_TIMER, REACT_S
from tests.companion.test_kill_failsafe import alive, descendants
from tests.companion.test_sitl_flights import (
    AUTOPILOTS,
    ON_GROUND,
    Autopilot,
    Companion,
    _trace_context,
)
from tests.profile_files import levels, sensors, write_profile_with
from tests.waiting import wait_until

CEILING = 120.0  # the default ceiling of a profile without a site


def _needed(kind: str, layer: float) -> dict[str, float]:
    """What the autopilot's own parameters must hold exactly (docs/companion.md)."""
    if kind == "arducopter":
        return {
            "FS_GCS_ENABLE": 1.0,  # companion lost: RTL
            "MAV_GCS_SYSID": 245.0,  # the companion is the GCS it watches
            "FENCE_ENABLE": 1.0,
            "FENCE_ACTION": 1.0,
            "BATT_FS_LOW_ACT": 2.0,
            "RTL_ALT": layer * 100.0,
        }
    return {
        "COM_OBL_RC_ACT": 3.0,  # offboard lost: Return
        "GF_ACTION": 3.0,
        "COM_LOW_BAT_ACT": 3.0,
        "RTL_RETURN_ALT": layer,
    }


@pytest.mark.timeout(600)
@pytest.mark.parametrize("backend", ["pymavlink", "mavsdk"])
@pytest.mark.parametrize("ap", AUTOPILOTS)
def test_a_killed_companion_leaves_the_vehicle_returning_by_its_own_safety_net(
    ap: Autopilot, backend: str, sitl_start: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    inst = sitl_start(ap.kind, speedup=ap.speedup)
    path = write_profile_with(
        tmp_path / "profile.yaml",
        "sitl-small",
        targets=[{"north": 1500.0, "east": 1500.0}, {"north": 2300.0, "east": 2300.0}],
        fleet={"vehicles": inst.index + 1},
        sensors=sensors(300.0, 100.0),
        policy={"levels": levels(600.0, 300.0, 150.0)},
        mission={"duration": 600.0},
        failsafe={"safety_net": "set"},
    )
    profile = load_profile(str(path))
    layer = profile.fleet.altitude + inst.index * profile.fleet.altitude_step
    obs = Observer(inst.observer_url, inst.sysid)
    comp = Companion(tmp_path, path, inst.index, inst.companion_url, backend, duration=600.0)
    context = _trace_context(obs, comp)
    try:
        wait_until(
            lambda: (
                (t := obs.snapshot()).armed
                and t.mode == ap.guided_custom
                and t.alt >= 20.0
                and t.distance >= 150.0
            ),
            300.0,
            "searching",
            context=context,
        )
        held = {name: obs.read_param(name) for name in _needed(ap.kind, layer)}
        fence_top = obs.read_param(
            "FENCE_ALT_MAX" if ap.kind == "arducopter" else "GF_MAX_VER_DIST"
        )
        loss_s = obs.read_param(LOSS_TIMER[ap.kind])
        children = descendants(comp.process.pid)
        boot = obs.snapshot().boot_s
        comp.kill()
        killed = time.monotonic()
        wait_until(lambda: obs.snapshot().mode == ap.rtl_custom, 60.0, "RTL", context=context)
        to_rtl = (time.monotonic() - killed, obs.snapshot().boot_s - boot)
        wait_until(
            lambda: (t := obs.snapshot()).landed_state == ON_GROUND and not t.armed,
            300.0,
            "landed and disarmed",
            context=context,
        )
    finally:
        comp.kill()
        obs.close()
    net = next(e for e in comp.events() if e["event"] == "safety_net")
    changed = {
        r["name"]: (r["before"], r["after"]) for r in net["params"] if r["before"] != r["after"]
    }
    texts = [x for x in obs.snapshot().texts if "ailsafe" in x]
    print(
        f"\n{ap.kind} {backend}: kill -> RTL {to_rtl[0]:.1f} wall s / {to_rtl[1]:.1f} vehicle s "
        f"(vehicle clock x{net['rate']}); landed, disarmed; failsafe texts {texts[:3]}; safety "
        f"net changed {changed}"
    )
    assert held == pytest.approx(_needed(ap.kind, layer)), held
    # the fence's ceiling: kept where already under the ceiling and above the layer band
    # (ArduCopter's stock FENCE_ALT_MAX 100 m), else the ceiling (PX4's stock 0: none)
    assert layer + 2.0 <= fence_top <= CEILING, fence_top
    assert alive(children) == [], children
    # by the vehicle's clock: the companion-loss time written (5 wall s in vehicle s), and
    # what the autopilot adds to it
    assert 0.0 < to_rtl[1] <= loss_s + REACT_S, (loss_s, to_rtl)
