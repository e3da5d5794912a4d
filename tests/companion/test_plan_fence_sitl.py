"""A profile made from a QGroundControl plan (`companion profile import`) flown on stock
ArduCopter SITL, as the field test flies field-duebendorf: the plan's five-vertex fence over
the east of the airfield becomes the site fence, the origin and area its bounding rectangle;
transit, a rehearsal target confirmed, RTL, landed. A second connection judges against the
plan's own polygon: every airborne GPS sample inside it, and the fence the vehicle stores equal
to it vertex for vertex."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from companion.cli import main
from companion.fence_from_profile import guidance_fence, profile_frame
from companion.mission.start_point import start_point
from companion.telemetry.mission_log import read_records
from mdm_profiles import load_profile
from tests import sitl
from tests.companion.sitl_observer import Observer
from tests.companion.test_field_mission_sitl import (
    HOME,
    ON_GROUND,
    RTL,
    SPEEDUP,
    _field_copy,
    _inside,
    _run,
    _stop,
    _vehicle_fence,
    _write,
)
from tests.waiting import wait_until

QGC_PLAN = Path(__file__).parents[1] / "data" / "qgc-duebendorf-east.plan"


def test_a_profile_imported_from_a_qgc_plan_flies_inside_the_plans_fence_on_arducopter(
    arducopter: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    inst = arducopter(speedup=SPEEDUP, home=",".join(map(str, (*HOME, 0))), battery_mah=20000)
    plan = json.loads(QGC_PLAN.read_text())
    polygon = [(lat, lon) for lat, lon in plan["geoFence"]["polygons"][0]["polygon"]]
    assert _inside(polygon, *HOME[:2]), "the plan's fence must hold the SITL home"
    base = _write(tmp_path / "base.yaml", _field_copy(inst.index + 1))
    imported = tmp_path / "from-plan.yaml"
    assert main(["profile", "import", str(QGC_PLAN), "--base", str(base), "--into",
                 str(imported), "--targets", "fit"]) == 0  # fmt: skip

    # The field test's recipe: a seed whose start point is 300-800 m from home, a real
    # rehearsal target 90 m from it towards the area's centre.
    profile = load_profile(imported)
    fence = guidance_fence(profile)
    home_ne = profile_frame(profile).to_local(*HOME)[:2]
    seed, start = next(
        (s, st)
        for s in range(500)
        if 300.0 <= math.dist(st := start_point(profile, s, inst.index, fence), home_ne) <= 800.0
    )
    centre = (profile.area.north / 2, profile.area.east / 2)
    toward = math.atan2(centre[1] - start[1], centre[0] - start[0])
    target = (
        round(start[0] + 90.0 * math.cos(toward), 1),
        round(start[1] + 90.0 * math.sin(toward), 1),
    )
    data = profile.model_dump(mode="json")
    data["targets"] = [{"north": target[0], "east": target[1]}]
    flown = _write(tmp_path / "flown.yaml", data)

    obs = Observer(inst.observer_url, inst.sysid)
    out = tmp_path / "flight"
    flight = _run(out, flown, inst, seed=seed)

    def context() -> str:
        return (
            f"observer: {obs.snapshot().modes} armed {obs.snapshot().armed}\n"
            f"{(out / 'companion.out').read_text(errors='replace')[-4000:]}"
        )

    def landed_after_rtl() -> bool:
        t = obs.snapshot()
        return t.landed_state == ON_GROUND and not t.armed and RTL in t.modes

    try:
        wait_until(landed_after_rtl, 600.0, "confirmed, RTL, landed, disarmed", context=context)
        assert flight.wait(timeout=400) == 0, context()
        records = read_records(out / f"mission-{inst.index}.jsonl")

        def first(event: str, **fields: object) -> dict[str, Any]:
            return next(
                r
                for r in records
                if r["event"] == event and all(r.get(k) == v for k, v in fields.items())
            )

        begin = first("transit", state="begin")
        assert (begin["to_north"], begin["to_east"]) == (round(start[0], 1), round(start[1], 1))
        (confirmation,) = [r for r in records if r["event"] == "confirmation"]
        assert (confirmation["north"], confirmation["east"]) == target
        assert first("end")["reason"] == "all targets"
        assert first("vehicle_fence", state="uploaded")["read_back"] == "equal"
        trace = obs.snapshot()
        airborne = [(lat, lon) for lat, lon, _alt, _mode in trace.track]  # alt > 1 m only
        outside = [p for p in airborne if not _inside(polygon, *p)]
        print(
            f"\nplan fence flight: seed {seed}, transit {begin['distance']} m, confirmed at "
            f"t={confirmation['t']} s; observer: {len(airborne)} airborne GPS samples, "
            f"{len(outside)} outside the plan's fence, {trace.distance:.0f} m flown, "
            f"modes {trace.modes}"
        )
        assert len(airborne) >= 100
        assert outside == [], f"{len(outside)} of {len(airborne)} samples outside: {outside[:5]}"
    finally:
        _stop(flight)
        obs.close()

    vertices, enabled = _vehicle_fence(inst.observer_url, inst.sysid)
    assert vertices == [(round(lat * 1e7), round(lon * 1e7)) for lat, lon in polygon]
    assert enabled == 1.0
    print(
        f"vehicle fence read back: {len(vertices)} vertices equal to the plan's, "
        f"FENCE_ENABLE {enabled:g}"
    )
