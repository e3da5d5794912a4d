"""A lawnmower team (policy.kind lm1, lm2) on the emulator: `companion fleet` flies
field-duebendorf's four vehicles, each its strip. Judged from the ground station's side (the
emulator's GLOBAL_POSITION_INT and HEARTBEAT on `--gcs`) and the emulator's own ground truth
(results.json is scored against its entered_range events): every point from entering the WGS84 fence to
the end of the search inside it,
the search's points along the lanes planned for that vehicle (the engine's plan cut to the
guidance fence, computed here), the lanes flown, every real target confirmed, no false one,
every vehicle back on the ground and disarmed after the search is called off (Ctrl-C) once
the emulator's log shows every real target confirmed."""

from __future__ import annotations

import json
import math
import os
import signal
from pathlib import Path

import pytest

from companion.fence_from_profile import profile_frame
from companion.telemetry.mission_log import read_records
from mdm_ground.fleet.scoring import EMULATOR_EVENTS
from mdm_montecarlo.study.variants import with_method
from mdm_profiles import builtin_profile, load_profile, write_profile
from tests.companion.sitl_team import inside
from tests.fleet_cli import start_fleet
from tests.ground.gcs_recorder import GcsRecorder
from tests.lawnmower_judge import judge_sweep, off_sweep, planned_lanes
from tests.mqtt_harness import free_port
from tests.waiting import wait_until

pytestmark = pytest.mark.usefixtures("fleet_processes")


SEED = 3
SPEEDUP = 100.0
TOLERANCE_M = 20.0
"""How far from its sweep a searching vehicle may be: the turns at the lane ends are flown as
the guidance's pursuit (5 m acceptance radius, 0.5 s velocity loop at 10 m/s): measured up to
15 m past a lane's end (inside the fence: the lanes end on the guidance fence, 20 m in)."""
OFFBOARD = 6 << 16
"""The emulator's PX4 persona's OFFBOARD (main mode 6 in bits 16-23): the companion steering."""
SEARCH_ALTITUDE_M = 35.0
"""Above this (the layers are 40-55 m) a vehicle is taken to be searching, not climbing or
landing."""


def _emulator_saw(out: Path, event: str) -> set[tuple[int, int]]:
    """(vehicle, target) of the emulator's ``confirmed`` or ``detected`` events (its ground
    truth, emulator-events.jsonl: the first time a vehicle's sensor had the target in range)."""
    path = out / EMULATOR_EVENTS
    if not path.exists():
        return set()
    return {
        (int(r["vehicle"]), int(r["target"])) for r in read_records(path) if r.get("event") == event
    }


def _passes(out: Path, vehicles: int) -> int:
    """Vehicles whose mission log shows a whole sweep of their lanes (``lawnmower_pass``)."""
    done = 0
    for i in range(vehicles):
        path = out / f"mission-{i}.jsonl"
        done += path.exists() and any(
            r.get("event") == "lawnmower_pass" for r in read_records(path)
        )
    return done


def _search_called_off(out: Path, method: str, real: set[int], vehicles: int) -> bool:
    """When the team lead calls the search off: every real target confirmed (the emulator's
    log); lm2 also once each vehicle has swept its lanes (its searches take most of its time
    near targets; lm1's confirmations come late in the sweep anyway)."""
    if {k for _, k in _emulator_saw(out, "confirmed")} < real:
        return False
    return method == "LM1" or _passes(out, vehicles) == vehicles


@pytest.mark.timeout(300)
@pytest.mark.parametrize("method", ["LM1", "LM2"])
def test_a_lawnmower_team_flies_its_strips_inside_the_fence_confirms_and_lands(
    method: str, fleet_processes: Path
) -> None:
    tmp = fleet_processes
    path = tmp / f"duebendorf-{method}.yaml"
    write_profile(with_method(builtin_profile("field-duebendorf"), method), path)
    profile = load_profile(str(path))
    port = free_port()
    gcs = GcsRecorder(port)
    out = tmp / "run"
    fleet = start_fleet("--profile", str(path), "--out", str(out), "--speedup", str(SPEEDUP),
                        "--seed", str(SEED), "--duration", str(profile.mission.duration), "--quiet", "--gcs", f"udpout:127.0.0.1:{port}",
                        output=tmp / "fleet.out")  # fmt: skip
    real = {k for k, t in enumerate(profile.targets) if not t.false_target}
    try:
        # The search is called off (Ctrl-C): each vehicle then flies RTL and the fleet waits
        # for the landings (a search ended by mission time stops the emulator in the air).
        wait_until(lambda: _search_called_off(out, method, real, profile.fleet.vehicles)
                   or fleet.poll() is not None, 200.0, "the search done",
                   context=lambda: (tmp / "fleet.out").read_text()[-3000:])  # fmt: skip
        if fleet.poll() is None:
            os.killpg(fleet.pid, signal.SIGINT)
        code = fleet.wait(timeout=120)
    finally:
        if fleet.poll() is None:
            os.killpg(fleet.pid, signal.SIGKILL)
        seen = gcs.close()
    assert code == 130, (tmp / "fleet.out").read_text()[-3000:]
    assert "fleet: every vehicle has landed" in (tmp / "fleet.out").read_text()
    result = json.loads((out / "results.json").read_text())
    assert result["stopped_by"] == "SIGINT"
    assert result["tnc"] == result["real_targets"] == len(real), result["first_confirmation"]
    assert result["false_confirmations"] == 0
    assert set(result["end_reasons"]) == {"0", "1", "2", "3"}
    assert profile.site is not None
    polygon = [(v.lat, v.lon) for v in profile.site.geofence]
    frame = profile_frame(profile)
    assert sorted(seen) == [1, 2, 3, 4]
    lines = []
    detected = _emulator_saw(out, "detected") if method == "LM2" else set()
    where = [(t.north, t.east) for t in profile.targets]
    r1 = profile.sensors[0].radius
    for sysid, v in sorted(seen.items()):
        i = sysid - 1
        assert v.armed_ever, f"vehicle {i} never armed"
        assert v.armed is False, f"vehicle {i} still armed at the end"
        assert v.track[-1][2] < 1.0, f"vehicle {i} not on the ground: {v.track[-1]}"
        # The emulator boots its vehicles on the area's edge, outside this fence (within the
        # site's start_margin); from the first point inside it to the end of the search (the
        # last point in OFFBOARD: then RTL flies home to the boot point) none is outside.
        flags = [inside(polygon, lat, lon) for lat, lon, _, _ in v.track]
        last = max(k for k, p in enumerate(v.track) if p[3] == OFFBOARD)
        outside = flags[flags.index(True) : last + 1].count(False)
        assert outside == 0, f"vehicle {i}: {outside} points of its flight outside the fence"
        lanes = planned_lanes(profile, SEED, i)
        guided = [
            frame.to_local(lat, lon, 0.0)[:2]
            for lat, lon, alt, mode in v.track
            if alt > SEARCH_ALTITUDE_M and mode == OFFBOARD
        ]  # the search, not the climb, the end action (RTL) or the landing
        # ... from the first point on the sweep on (before it: the transit; an lm2 vehicle
        # may detect a target before it reaches its lanes)
        first = next(k for k, p in enumerate(guided) if off_sweep(p, lanes) < TOLERANCE_M)
        sweep = judge_sweep(guided[first:], lanes, TOLERANCE_M)
        # every point off the sweep is in a confirmation search round a target this vehicle
        # detected: within r1 (the point of detection) + r1 (the spiral) of it (lm2 only)
        near = [where[k] for j, k in detected if j == i]
        away = [p for p in guided[first:] if off_sweep(p, lanes) > TOLERANCE_M]
        stray = [p for p in away if all(math.dist(p, q) > 2 * r1 + TOLERANCE_M for q in near)]
        lines.append(
            f"{sweep.line(i)}; {len(away)} points in searches; {len(v.track)} GCS positions"
        )
        assert stray == [], f"{lines[-1]}: {len(stray)} points off the sweep, not searching"
        assert sweep.flown >= 1, lines[-1]
        if method == "LM1":
            assert away == [], lines[-1]
    print("\n" + "\n".join(lines))
    assert (out / "map.png").stat().st_size > 10_000
