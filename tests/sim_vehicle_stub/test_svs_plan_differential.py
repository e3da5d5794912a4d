"""Differential test of AUTO: one QGroundControl plan (a Survey expanded into waypoints, as
QGroundControl stores it, tests/qgc_plan.py) uploaded through MAVSDK's QGC import and flown by
the emulator's persona and by the real autopilot's SITL (tests/mavsdk_flights.py). Both must
report the same mission items in the same order, pass every survey point within the acceptance
radius, and fly paths that agree within PATH_TOLERANCE; the figures are printed (docs/protocol.md,
*Missions*, has the measured table)."""

from __future__ import annotations

import asyncio
import logging
import math
from collections.abc import Callable

import numpy as np
import pytest

from companion.link.address import parse_address
from tests.emulator_harness import PROFILE, free_udp_base, make_config, running_emulator
from tests.mavsdk_flights import PlanFlight, fly_plan
from tests.qgc_plan import lawnmower, plan_text, survey_plan
from tests.sitl import SitlInstance

log = logging.getLogger(__name__)
PERSONA = {"arducopter": "ardupilot", "px4": "px4"}
HOME = (PROFILE.origin.lat, PROFILE.origin.lon, PROFILE.origin.alt)
SPEEDUP = {"arducopter": 3.0, "px4": 4.0}
"""ArduCopter's DISARM_DELAY (10 s on the ground) must not pass between MAVSDK's arm and its
takeoff (a mode change and a command, in wall time)."""
SURVEY = lawnmower(3, 80.0, 25.0, (20.0, -20.0))
ALT = 15.0
SPEED = 8.0
PASS_RADIUS = {"emulator": 2.5, "sitl": 6.0}
"""m: each survey point is passed this close (acceptance radii 2 m; PX4 SITL turns early,
passing up to 4.2 m off in the first run)."""
LANDING_AGREEMENT = 8.0
"""m between where the two touched down (the rally point 50 m north, nearer than home; PX4 SITL
touched down 3.8-5.5 m past it in three runs)."""
PATH_TOLERANCE = {"arducopter": 7.0, "px4": 9.0}
"""m: the largest distance from a point of one survey path to the other path (PX4: 6.3-7.1 m
in three runs; ArduCopter: 6.27 m in four runs, 2026-12-02, the same to 1 mm each time;
ArduCopter's S-curves and PX4's acceptance-radius turns round the corners the lag loop flies
square; figures in benchmarks/README.md, "AUTO against SITL")."""


def _survey(path: list[tuple[float, float, float]]) -> np.ndarray:
    """The survey part of a path: at the survey's altitude, from the first to the last point."""
    pts = np.array([(n, e) for n, e, a in path if abs(a - ALT) < 1.0])
    first = np.argmin(np.hypot(*(pts - SURVEY[0]).T))
    last = len(pts) - np.argmin(np.hypot(*(pts[::-1] - SURVEY[-1]).T))
    return pts[first:last]


def _distance(a: np.ndarray, b: np.ndarray) -> float:
    """The largest distance from a point of ``a`` to the nearest point of ``b`` (10 Hz
    samples: at 8 m/s 0.8 m apart, which bounds the error of this measure)."""
    return float(max(np.min(np.hypot(*(b - p).T)) for p in a))


def _fly(url: str, autopilot: str) -> PlanFlight:
    plan = plan_text(survey_plan(HOME, SURVEY, ALT, 3 if autopilot == "arducopter" else 12))
    return asyncio.run(fly_plan(url, plan, ardupilot=autopilot == "arducopter", speed=SPEED))


@pytest.mark.timeout(600)
@pytest.mark.parametrize("autopilot", ["arducopter", "px4"])
def test_a_qgc_plan_is_flown_like_the_real_autopilot_flies_it(
    autopilot: str, sitl_start: Callable[..., SitlInstance], monkeypatch: pytest.MonkeyPatch
) -> None:
    base = free_udp_base(1)
    # Booted at the profile origin, which is HOME (the SITL's home too).
    cfg = make_config(
        1,
        base,
        personas=(PERSONA[autopilot],),
        speedup=SPEEDUP[autopilot],
        start_positions=((0.0, 0.0),),
    )
    with running_emulator(cfg):
        emulated = _fly(f"udpin://127.0.0.1:{base}", autopilot)
    home = ",".join(f"{x:g}" for x in HOME)
    if autopilot == "px4":
        monkeypatch.setenv("PX4_SIM_SPEED_FACTOR", str(SPEEDUP[autopilot]))
        inst = sitl_start(autopilot, home=home)
    else:
        inst = sitl_start(autopilot, home=home + ",0", speedup=SPEEDUP[autopilot])
    real = _fly(parse_address(inst.companion_url).mavsdk_url(), autopilot)
    e, r = _survey(emulated.path), _survey(real.path)
    misses = {
        name: [min(math.hypot(n - sn, e - se) for n, e, _ in rec.path) for sn, se in SURVEY]
        for name, rec in (("emulator", emulated), ("sitl", real))
    }
    path = max(_distance(e, r), _distance(r, e))
    landed = {
        k: tuple(round(x, 2) for x in rec.landed_at)
        for k, rec in (("emulator", emulated), ("sitl", real))
        if rec.landed_at
    }
    print(
        f"\n{autopilot}: progress emulator {emulated.progress} sitl {real.progress}; survey "
        f"point misses emulator {np.round(misses['emulator'], 2).tolist()} sitl "
        f"{np.round(misses['sitl'], 2).tolist()}; path distance {path:.2f} m; landed at "
        f"{landed}; samples {len(e)} / {len(r)}"
    )
    assert emulated.uploaded == real.uploaded
    assert emulated.downloaded == real.downloaded
    assert emulated.progress == real.progress
    assert max(misses["emulator"]) < PASS_RADIUS["emulator"]
    assert max(misses["sitl"]) < PASS_RADIUS["sitl"]
    assert emulated.landed_at is not None
    assert real.landed_at is not None
    landing = math.dist(emulated.landed_at, real.landed_at)
    assert landing < LANDING_AGREEMENT, (emulated.landed_at, real.landed_at)
    assert path < PATH_TOLERANCE[autopilot], inst.log()[-1500:]
