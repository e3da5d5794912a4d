"""A lawnmower team (policy.kind lm1, lm2) on the emulator: `companion fleet` flies
field-duebendorf's four vehicles, each its strip. Judged from the ground station's side (the
emulator's GLOBAL_POSITION_INT and HEARTBEAT on `--gcs`) and the emulator's own ground truth
(results.json is scored against its entered_range events): every point inside the WGS84 fence,
the search's points along the lanes planned for that vehicle (the engine's plan cut to the
guidance fence, computed here), the lanes flown, every real target confirmed, no false one,
every vehicle back on the ground and disarmed."""

from __future__ import annotations

import json
import math
import os
import signal
from pathlib import Path

import pytest

from companion.fence_from_profile import profile_frame
from mdm_montecarlo.study.variants import with_method
from mdm_profiles import builtin_profile, load_profile, write_profile
from tests.companion.sitl_team import inside
from tests.fleet_cli import start_fleet
from tests.ground.gcs_recorder import GcsRecorder
from tests.lawnmower_judge import judge_sweep, planned_lanes
from tests.mqtt_harness import free_port

pytestmark = pytest.mark.usefixtures("fleet_processes")

SEED = 3
SPEEDUP = 100.0
TOLERANCE_M = 15.0
"""How far from its sweep a searching vehicle may be: the turns at the lane ends are flown as
the guidance's pursuit (5 m acceptance radius, 0.5 s velocity loop at 10 m/s)."""
OFFBOARD = 6 << 16
"""The emulator's PX4 persona's OFFBOARD (main mode 6 in bits 16-23): the companion steering."""
SEARCH_ALTITUDE_M = 35.0
"""Above this (the layers are 40-55 m) a vehicle is taken to be searching, not climbing or
landing."""
ON_LANES = {"LM1": 0.97, "LM2": 0.4}
"""Least share of a vehicle's search points on its sweep: LM1 never leaves it; LM2 leaves it
for each confirmation search (spirals up to r1 = 300 m round a detection)."""


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
                        "--seed", str(SEED), "--quiet", "--gcs", f"udpout:127.0.0.1:{port}",
                        output=tmp / "fleet.out")  # fmt: skip
    try:
        code = fleet.wait(timeout=240)
    finally:
        if fleet.poll() is None:
            os.killpg(fleet.pid, signal.SIGKILL)
        seen = gcs.close()
    assert code == 0, (tmp / "fleet.out").read_text()[-3000:]
    result = json.loads((out / "results.json").read_text())
    assert result["complete"], result["ends"]
    assert result["tnc"] == result["real_targets"] == 3, result["first_confirmation"]
    assert result["false_confirmations"] == 0
    assert profile.site is not None
    polygon = [(v.lat, v.lon) for v in profile.site.geofence]
    frame = profile_frame(profile)
    assert sorted(seen) == [1, 2, 3, 4]
    lines = []
    for sysid, v in sorted(seen.items()):
        i = sysid - 1
        assert v.armed_ever, f"vehicle {i} never armed"
        assert v.armed is False, f"vehicle {i} still armed at the end"
        assert v.track[-1][2] < 1.0, f"vehicle {i} not on the ground: {v.track[-1]}"
        outside = [p for p in v.track if not inside(polygon, p[0], p[1])]
        assert not outside, f"vehicle {i}: {len(outside)} points outside the fence"
        lanes = planned_lanes(profile, SEED, i)
        guided = [
            frame.to_local(lat, lon, 0.0)[:2]
            for lat, lon, alt, mode in v.track
            if alt > SEARCH_ALTITUDE_M and mode == OFFBOARD
        ]  # the search, not the climb, the end action (RTL) or the landing
        start = lanes[0]  # ... from the first lane's end on (before it: the transit)
        first = next(k for k, p in enumerate(guided) if math.dist(p, start) < TOLERANCE_M)
        sweep = judge_sweep(guided[first:], lanes, TOLERANCE_M)
        lines.append(sweep.line(i))
        assert sweep.on_sweep >= ON_LANES[method], lines[-1]
        assert sweep.flown >= 1, lines[-1]
    print("\n" + "\n".join(lines))
    assert (out / "map.png").stat().st_size > 10_000
