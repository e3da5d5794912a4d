"""One lawnmower vehicle (policy.kind lm1) on stock ArduCopter SITL: `companion run` flies its
strip of field-duebendorf (the vehicle's cell of the team's plan, lanes cut to the guidance
fence) from its start point, confirms the rehearsal target placed past the end of its last
lane, and RTLs home. Judged from the autopilot's second link (SERIAL1, tests/companion/
sitl_observer.py): every airborne GPS sample inside the WGS84 fence, the search's samples on
the planned lanes (computed here from the profile and seed), the lanes flown, RTL, landed and
disarmed; the run map drawn."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from companion.fence_from_profile import guidance_fence, profile_frame
from companion.mission.start_point import start_point
from companion.telemetry.mission_log import read_records
from mdm_profiles import load_profile
from tests import sitl
from tests.companion.sitl_observer import Observer
from tests.companion.sitl_team import inside
from tests.lawnmower_judge import judge_sweep, planned_lanes
from tests.waiting import wait_until

SPEEDUP = 5
SEED = 3
VEHICLE = 5
"""The profile's vehicle flown (of VEHICLE + 1): its cell, lanes and start point are those the test
was measured with, on whichever SITL instance is free."""
GUIDED, RTL = 4, 6  # ArduCopter custom modes
ON_GROUND = 1  # MAV_LANDED_STATE_ON_GROUND
TOLERANCE_M = 40.0
"""How far from its sweep a searching vehicle may be. A lane's end is reached within the 5 m
acceptance radius and the next one pursued at once; ArduCopter's GUIDED braking (its
acceleration limits) carries it on past the turn (measured on this SITL at 10 m/s: 27 and 29 m
in two runs; the emulator's 0.5 s velocity loop: 15 m), and the pursuit of the next lane's end
closes that offset along the lane. Lanes are 300 m apart: 40 m still names the lane."""
PAST_END_M = 100.0
"""The target lies this far beyond the last lane's end (or at the area's edge): confirmed
(r2 150 m) in the lane's last 50-150 m, so the whole strip is flown before the search ends."""


def _strip_profile(folder: Path, vehicles: int) -> dict[str, Any]:
    """field-duebendorf as an lm1 team of ``vehicles`` (the last is the SITL's), a 150 m
    camera (lanes 300 m apart: a strip of two lanes, ~1.5 km), virtual sensors."""
    p = load_profile("field-duebendorf").model_dump(mode="json", exclude_none=True)
    p["name"] = f"lawnmower-sitl-{os.getpid()}"
    p["fleet"]["vehicles"] = vehicles
    p["fleet"]["altitude_step"] = 0.0  # one vehicle: the first layer (40 m)
    p["sensor_source"] = {"kind": "virtual"}
    p["sensors"] = [
        {"name": "rf-detection", "radius": 400.0},
        {"name": "camera-confirmation", "radius": 150.0},
    ]
    p["policy"] = {"kind": "lm1", "levels": [{"distribution": "US", "step": 200.0}]}
    p["mission"] = {"duration": 900.0, "ts_cap": 900.0}
    return p


def _past_the_end(lanes: np.ndarray, area: tuple[float, float]) -> tuple[float, float]:
    end, before = lanes[-1], lanes[-2]
    along = (end - before) / float(np.hypot(*(end - before)))
    point = np.clip(end + PAST_END_M * along, 0.0, area)
    return round(float(point[0]), 1), round(float(point[1]), 1)


def test_a_lawnmower_vehicle_flies_its_strip_inside_the_fence_and_lands_on_arducopter(
    arducopter: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    # the profile's vehicle VEHICLE of VEHICLE + 1, whatever instance flies it (its system id)
    field = _strip_profile(tmp_path, vehicles=VEHICLE + 1)
    probe = tmp_path / "probe.yaml"
    probe.write_text(yaml.safe_dump(field, sort_keys=False))
    profile = load_profile(str(probe))
    lanes = planned_lanes(profile, SEED, VEHICLE)
    area = (profile.area.north, profile.area.east)
    target = _past_the_end(lanes, area)
    field["targets"] = [{"north": target[0], "east": target[1]}]
    path = tmp_path / "strip.yaml"
    path.write_text(yaml.safe_dump(field, sort_keys=False))
    profile = load_profile(str(path))
    frame = profile_frame(profile)
    start = start_point(profile, SEED, VEHICLE, guidance_fence(profile))
    lat, lon, _ = frame.to_geodetic(*start, 0.0)
    home = f"{lat:.7f},{lon:.7f},{profile.origin.alt:g},0"
    inst = arducopter(speedup=SPEEDUP, home=home, battery_mah=20000)
    assert profile.site is not None
    polygon = [(v.lat, v.lon) for v in profile.site.geofence]
    obs = Observer(inst.observer_url, inst.sysid)
    out = tmp_path / "run"
    out.mkdir()
    with (out / "companion.out").open("wb") as f:
        flight = subprocess.Popen(
            [sys.executable, "-m", "companion.cli", "run", "--profile", str(path),
             "--vehicle", str(VEHICLE), "--system-id", str(inst.sysid),
             "--connect", inst.companion_url, "--log-dir", str(out),
             "--seed", str(SEED), "--land-wait", "400", "--flight-log-wait", "0"],
            stdout=f, stderr=subprocess.STDOUT, start_new_session=True,
            env=dict(os.environ, PYTHONUNBUFFERED="1"),
        )  # fmt: skip

    def context() -> str:
        return (
            f"observer: modes {obs.snapshot().modes}, armed {obs.snapshot().armed}\n"
            + (out / "companion.out").read_text(errors="replace")[-4000:]
        )

    def landed_after_rtl() -> bool:
        t = obs.snapshot()
        return t.landed_state == ON_GROUND and t.armed_ever and not t.armed and RTL in t.modes

    try:
        wait_until(landed_after_rtl, 400.0, "the strip flown, RTL, landed", context=context)
        assert flight.wait(timeout=120) == 0, context()
        trace = obs.snapshot()
    finally:
        if flight.poll() is None:
            flight.kill()
            flight.wait()
        obs.close()
    records = read_records(out / f"mission-{VEHICLE}.jsonl")
    (confirmation,) = [r for r in records if r["event"] == "confirmation"]
    assert (confirmation["north"], confirmation["east"]) == target
    assert next(r for r in records if r["event"] == "end")["reason"] == "all targets"
    airborne = [(lat, lon) for lat, lon, _alt, _mode in trace.track]
    outside = [p for p in airborne if not inside(polygon, *p)]
    searching = [
        frame.to_local(lat, lon, 0.0)[:2]
        for lat, lon, alt, mode in trace.track
        if mode == GUIDED and alt > 0.9 * profile.fleet.altitude
    ]
    first = next(k for k, p in enumerate(searching) if math.dist(p, lanes[0]) < TOLERANCE_M)
    sweep = judge_sweep(searching[first:], lanes, TOLERANCE_M, share=0.7)
    print(
        f"\nlawnmower on ArduCopter SITL: vehicle {VEHICLE} of {VEHICLE + 1}, "
        f"{sweep.line(VEHICLE)}; {len(airborne)} airborne GPS samples, {len(outside)} outside "
        f"the fence, {trace.distance:.0f} m flown, confirmed {target} at t={confirmation['t']} "
        f"s, modes {trace.modes}, landed_state {trace.landed_state}, armed {trace.armed}; "
        f"map {out / f'map-{VEHICLE}.png'}"
    )
    assert len(airborne) >= 100
    assert outside == [], f"{len(outside)} of {len(airborne)} samples outside: {outside[:5]}"
    assert sweep.on_sweep >= 0.97, sweep.line(VEHICLE)
    assert sweep.flown == sweep.lanes, sweep.line(VEHICLE)
    assert (out / f"map-{VEHICLE}.png").stat().st_size > 10_000
