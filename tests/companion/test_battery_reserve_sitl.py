"""The battery reserve that knows the way home, on stock ArduCopter SITL with a small pack: a
field search (Duebendorf, booted in the fence's north-east corner, far from most of the area)
that no target ends, flown twice at once by two fresh instances booted at the same point, as the
same vehicle of the profile with the same seed (the second under its own system id). With
``site.battery_reserve`` the companion turns the vehicle home while the pack still holds the
flight home plus the reserve, and it lands with at least the reserve left; with the fixed
``battery_min`` alone it turns at 20 % whatever the distance. Judged on the autopilot's second
link (SERIAL1): SYS_STATUS battery_remaining when RTL began and once landed and disarmed."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest
import yaml

from tests import sitl
from tests.companion.sitl_observer import Observer
from tests.profile_files import blind_field_search
from tests.waiting import wait_until

SPEEDUP = 5
HOME = "47.405893,8.663214,440.0,0"  # inside the Duebendorf fence, its north-east corner
PACK_MAH = 9000  # about 1100 vehicle s of flight: the way home is 10-20 % of it
RTL = 6  # ArduCopter custom mode
ON_GROUND = 1  # MAV_LANDED_STATE_ON_GROUND
BATTERY_MIN = 20.0
RESERVE = 15.0
SEED = 3


def _profile(vehicles: int, reserve: float | None) -> dict[str, Any]:
    """field-duebendorf for one long search no target ends: sensors of a few metres, the real
    target in the area's far corner, time enough for the pack to run down."""
    p = blind_field_search(f"battery-sitl-{os.getpid()}", vehicles, 3000.0)
    p["site"]["battery_min"] = BATTERY_MIN
    p["site"]["battery_reserve"] = reserve
    return p


def _fly(inst: sitl.SitlInstance, out: Path, reserve: float | None) -> tuple[int, int, str]:
    """Vehicle 0's flight on ``inst``: the battery when RTL began and once landed and disarmed
    (the autopilot's SYS_STATUS on its second link), and the companion's last lines."""
    out.mkdir(parents=True)
    path = out / "profile.yaml"
    path.write_text(yaml.safe_dump(_profile(1, reserve), sort_keys=False))
    obs = Observer(inst.observer_url, inst.sysid)
    with (out / "companion.out").open("ab") as f:
        companion = subprocess.Popen(
            [sys.executable, "-m", "companion.cli", "run", "--profile", str(path),
             "--vehicle", "0", "--system-id", str(inst.sysid), "--connect", inst.companion_url,
             "--log-dir", str(out), "--seed", str(SEED), "--land-wait", "600", "--flight-log-wait", "0"],
            stdout=f, stderr=subprocess.STDOUT, start_new_session=True,
            env=dict(os.environ, PYTHONUNBUFFERED="1"),
        )  # fmt: skip

    def context() -> str:
        t = obs.snapshot()
        said = (out / "companion.out").read_text(errors="replace")[-3000:]
        return f"observer: modes {t.modes} battery {t.battery}% armed {t.armed}\n{said}"

    def landed_after_rtl() -> bool:
        t = obs.snapshot()
        return t.landed_state == ON_GROUND and not t.armed and RTL in t.modes

    try:
        wait_until(landed_after_rtl, 900.0, "RTL by itself, landed, disarmed", context=context)
        assert companion.wait(timeout=400) == 1, context()  # a battery end: a fault end
        trace = obs.snapshot()
        assert trace.battery >= 0, "the observer never heard SYS_STATUS's battery"
        at_rtl = trace.mode_battery[trace.modes.index(RTL)]
        said = (out / "companion.out").read_text(errors="replace")
        return at_rtl, trace.battery, said
    finally:
        if companion.poll() is None:
            os.killpg(companion.pid, signal.SIGKILL)
            companion.wait()
        obs.close()
        inst.stop()


@pytest.mark.timeout(1500)  # two flights side by side, each up to 900 wall s
def test_the_reserve_rule_turns_home_in_time_and_lands_with_the_reserve(
    arducopter: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    # started one after the other (each takes the next free instance index), flown at once
    first = arducopter(speedup=SPEEDUP, home=HOME, battery_mah=PACK_MAH)
    second = arducopter(speedup=SPEEDUP, home=HOME, battery_mah=PACK_MAH)
    with ThreadPoolExecutor(2) as pool:
        reserve = pool.submit(_fly, first, tmp_path / "reserve", RESERVE)
        fixed = pool.submit(_fly, second, tmp_path / "fixed", None)
        turned, landed, said = reserve.result()
        fixed_turned, fixed_landed, fixed_said = fixed.result()
    assert "home needs" in said, said[-3000:]
    print(
        f"\nbattery, reserve rule ({RESERVE:g} % + the way home): RTL at {turned} %, landed "
        f"with {landed} %; fixed rule ({BATTERY_MIN:g} %): RTL at {fixed_turned} %, landed "
        f"with {fixed_landed} %"
    )
    assert turned > BATTERY_MIN, "the fixed minimum, not the reserve rule, turned it home"
    assert landed >= RESERVE
    assert fixed_turned < BATTERY_MIN
    assert "home needs" not in fixed_said
