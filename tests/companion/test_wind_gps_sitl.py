"""Weather and GPS on real autopilot code: the Duebendorf field search on stock ArduCopter SITL
in a 9 m/s wind with turbulence (SIM_WIND_SPD, SIM_WIND_TURB), the wind turning twice during the
search (SIM_WIND_DIR) and a GPS glitch of about 22 m for 10 vehicle s (SIM_GPS1_GLTCH_X, set on
the autopilot's second link while it flies). Judged on that link: the vehicle searches (GUIDED,
at its layer, some km flown), every airborne position stays inside the site fence, the
altitude stays within the companion's layer warning band (LAYER_TOLERANCE_M, held
LAYER_HOLD_S) while it searches, and it lands and disarms after the RTL. The figures are
printed."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import yaml

from companion.fence_from_profile import fence_for, profile_frame
from companion.mission.layer_watch import LAYER_HOLD_S, LAYER_TOLERANCE_M
from mdm_profiles import load_profile
from tests import sitl
from tests.companion.sitl_observer import Observer, Trace
from tests.profile_files import blind_field_search
from tests.waiting import wait_until

SPEEDUP = 5
HOME = "47.405893,8.663214,440.0,0"  # inside the Duebendorf fence, its north-east corner
GUIDED, RTL = 4, 6  # ArduCopter custom modes
ON_GROUND = 1  # MAV_LANDED_STATE_ON_GROUND
ALTITUDE = 40.0
WEATHER = "SIM_WIND_SPD 9\nSIM_WIND_TURB 3\nSIM_WIND_DIR 270\n"
GLITCH_DEG = 0.0002  # latitude: 22 m north
SEARCH_S = 300.0
POSITION_HZ = 10.0  # GLOBAL_POSITION_INT as the observer asks for it (vehicle time)


def _profile(vehicles: int) -> dict[str, object]:
    p = blind_field_search(f"wind-sitl-{os.getpid()}", vehicles, SEARCH_S)
    p["fleet"]["altitude"] = ALTITUDE
    return p


def _searching(t: Trace) -> list[tuple[float, float, float, float]]:
    """(stamp, lat, lon, alt) of every GUIDED position once the vehicle first reached its layer
    (transit and search), until the RTL."""
    rows, reached = [], False
    for (lat, lon, alt, mode), stamp in zip(t.track, t.stamps, strict=True):
        if mode == RTL:
            break
        reached |= mode == GUIDED and alt >= ALTITUDE - LAYER_TOLERANCE_M
        if reached and mode == GUIDED:
            rows.append((stamp, lat, lon, alt))
    return rows


def _longest_off_layer(rows: list[tuple[float, float, float, float]]) -> float:
    """The longest stretch off the layer by more than the tolerance, vehicle s (positions at
    the observer's POSITION_HZ of the vehicle's clock)."""
    longest = run = 0
    for _, _, _, alt in rows:
        run = run + 1 if abs(alt - ALTITUDE) > LAYER_TOLERANCE_M else 0
        longest = max(longest, run)
    return longest / POSITION_HZ


@pytest.mark.timeout(1200)
def test_searches_in_wind_and_a_gps_glitch_inside_the_fence_and_its_layer(
    arducopter: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    weather = tmp_path / "weather.parm"
    weather.write_text(WEATHER)
    inst = arducopter(speedup=SPEEDUP, home=HOME, defaults=weather, battery_mah=20000)
    profile = _profile(inst.index + 1)
    path = tmp_path / "profile.yaml"
    path.write_text(yaml.safe_dump(profile, sort_keys=False))
    out = tmp_path / "run"
    out.mkdir()
    obs = Observer(inst.observer_url, inst.sysid)
    with (out / "companion.out").open("ab") as f:
        companion = subprocess.Popen(
            [sys.executable, "-m", "companion.cli", "run", "--profile", str(path),
             "--vehicle", str(inst.index), "--connect", inst.companion_url, "--log-dir", str(out),
             "--seed", "1", "--land-wait", "600", "--flight-log-wait", "0", "--no-map"],
            stdout=f, stderr=subprocess.STDOUT, start_new_session=True,
            env=dict(os.environ, PYTHONUNBUFFERED="1"),
        )  # fmt: skip

    def context() -> str:
        t = obs.snapshot()
        said = (out / "companion.out").read_text(errors="replace")[-3000:]
        return f"observer: modes {t.modes} alt {t.alt:.1f} texts {t.texts[-5:]}\n{said}"

    try:
        obs.await_state(
            lambda t: t.mode == GUIDED and t.alt >= ALTITUDE - LAYER_TOLERANCE_M,
            300.0,
            "guided at the layer",
            context=context,
        )
        obs.hold(60.0, "flying", context=context)
        obs.set_param("SIM_WIND_DIR", 90.0)  # the wind turns round
        obs.hold(40.0, "flying", context=context)
        obs.set_param("SIM_GPS1_GLTCH_X", GLITCH_DEG)
        obs.hold(10.0, "flying", context=context)
        echoed = obs.snapshot().params  # the SITL has these parameters and took the values
        assert echoed.get("SIM_GPS1_GLTCH_X") == pytest.approx(GLITCH_DEG), echoed
        assert echoed.get("SIM_WIND_DIR") == 90.0, echoed
        obs.set_param("SIM_GPS1_GLTCH_X", 0.0)
        obs.set_param("SIM_WIND_DIR", 0.0)  # and again, from the north
        wait_until(
            lambda: (
                (t := obs.snapshot()).landed_state == ON_GROUND and not t.armed and RTL in t.modes
            ),
            600.0,
            "RTL at mission time, landed, disarmed",
            context=context,
        )
        assert companion.wait(timeout=60) == 0, context()
    finally:
        if companion.poll() is None:
            os.killpg(companion.pid, signal.SIGKILL)
            companion.wait()
        obs.close()

    trace = obs.snapshot()
    load = load_profile(str(path))
    fence, frame = fence_for(load), profile_frame(load)
    points = [np.array(frame.to_local(lat, lon, 0.0)[:2]) for lat, lon, _, _ in trace.track]
    outside = [float(np.hypot(*(fence.clamp(p) - p))) for p in points if not fence.contains(p)]
    rows = _searching(trace)
    off = [abs(alt - ALTITUDE) for _, _, _, alt in rows]
    within = sum(d <= LAYER_TOLERANCE_M for d in off) / len(off)
    longest = _longest_off_layer(rows)
    glitch = [t for t in trace.texts if "glitch" in t.lower() or "gps" in t.lower()]
    print(
        f"\nwind 9 m/s, turbulence 3, direction 270 -> 90 -> 0; GPS glitch {GLITCH_DEG} deg "
        f"latitude for 10 s: {len(points)} airborne positions, {len(outside)} outside the fence "
        f"(worst {max(outside, default=0.0):.1f} m); {len(rows)} at the layer in GUIDED: "
        f"{within:.1%} within {LAYER_TOLERANCE_M:g} m of {ALTITUDE:g} m, largest deviation "
        f"{max(off):.2f} m, longest stretch off {longest:.1f} vehicle s; {trace.distance:.0f} m "
        f"flown, max ground speed {trace.max_speed:.1f} m/s; the autopilot said {glitch}"
    )
    assert trace.distance >= 1500.0, "it did not search"
    assert len(rows) >= 200
    assert outside == [], f"{len(outside)} positions outside the fence, worst {max(outside):.1f} m"
    # the companion's warning band: off by more than the tolerance for LAYER_HOLD_S vehicle s
    assert longest < LAYER_HOLD_S, f"off the layer for {longest:.1f} vehicle s"
