"""``failsafe.safety_net: check`` on stock ArduCopter and PX4 SITL: nothing is written, the
vehicle is refused before arming, exit 2, the refusal naming each parameter not as needed with
the value the vehicle holds. Judged on the autopilot's second link: never armed, and each named
parameter still holds its stock value after the companion ended. (The site's fence is the
vehicle fence's, uploaded and switched on in every mode, companion/mission/vehicle_fence.py:
on ArduCopter it writes FENCE_TYPE 7 -> 5 and FENCE_ENABLE 0 -> 1 before the check reads
them, so they are not among the parameters refused.)"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
import yaml

from tests import sitl
from tests.companion.sitl_observer import Observer
from tests.companion.test_autopilot_failsafes_sitl import HOME, _profile
from tests.companion.test_sitl_flights import AUTOPILOTS, Autopilot, Companion

STOCK_WRONG = {
    "arducopter": {
        "FS_GCS_ENABLE": 0.0,
        "MAV_GCS_SYSID": 255.0,
        "FS_GCS_TIMEOUT": 5.0,  # 5 s of a 5x vehicle's clock is 1 wall s
        "BATT_FS_LOW_ACT": 0.0,
        "BATT_LOW_MAH": 0.0,
        "RTL_ALT": 1500.0,  # 15 m: under the 30 m layer's band
    },
    "px4": {
        "GF_ACTION": 2.0,
        "GF_MAX_VER_DIST": 0.0,
        "COM_OBL_RC_ACT": 0.0,
        "BAT_CRIT_THR": 0.07,
    },
}
"""What the stock SITLs hold that the safety net needs otherwise (measured: the ``before`` of
the kill test's ``safety_net`` records)."""


@pytest.mark.timeout(240)
@pytest.mark.parametrize("ap", AUTOPILOTS)
def test_check_refuses_a_stock_vehicle_before_arming_naming_each_parameter(
    ap: Autopilot, sitl_start: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    inst = sitl_start(
        ap.kind, speedup=ap.speedup, home=f"{HOME},0" if ap.kind == "arducopter" else HOME
    )
    path = _profile(tmp_path / "profile.yaml", inst.index + 1)
    profile = yaml.safe_load(path.read_text())
    profile["failsafe"] = {"safety_net": "check"}
    path.write_text(yaml.safe_dump(profile, sort_keys=False))
    obs = Observer(inst.observer_url, inst.sysid)
    comp = Companion(tmp_path, path, inst.index, inst.companion_url, "pymavlink", 600.0)
    try:
        status = comp.process.wait(timeout=180)
        held = {name: obs.read_param(name) for name in STOCK_WRONG[ap.kind]}
        armed_ever = obs.snapshot().armed_ever
    finally:
        comp.kill()
        obs.close()
    said = comp.output()
    refusal = next((line for line in said.splitlines() if "not armed:" in line), "")
    print(f"\n{ap.kind} check: exit {status}; {refusal.strip()}")
    assert status == 2, said[-3000:]
    assert not armed_ever
    assert held == pytest.approx(STOCK_WRONG[ap.kind])  # checked, not written
    for name, value in STOCK_WRONG[ap.kind].items():
        assert f"{name} is {value:g}, needs" in refusal, said[-3000:]
    net = next(e for e in comp.events() if e["event"] == "safety_net")
    assert (net["mode"], net["state"]) == ("check", "refused"), net
    recorded = {r["name"]: (r["before"], r["after"]) for r in net["params"]}
    for name, value in STOCK_WRONG[ap.kind].items():  # recorded as read, and left
        assert recorded[name] == (pytest.approx(value), pytest.approx(value)), recorded
