"""`companion fleet --vehicles-file` over SITL instances the test started itself (ArduCopter and
PX4, each booted at its start point), with system ids that are not index + 1: the fleet flies
exactly those vehicles, no emulator; each autopilot's second link judges the flight."""

from __future__ import annotations

import json
import os
import signal
from collections.abc import Callable
from pathlib import Path

import yaml

from mdm_ground.fleet.sitl_team import boot_points
from mdm_profiles import load_profile
from tests import sitl
from tests.companion.sitl_observer import Observer
from tests.companion.sitl_team import fence_polygon, figures, team_profile
from tests.fleet_cli import start_fleet

SPEEDUP = 2.0
SEED = 5


def test_a_fleet_file_flies_the_listed_sitl_vehicles_under_their_own_system_ids(
    arducopter: Callable[..., sitl.SitlInstance],
    px4: Callable[..., sitl.SitlInstance],
    tmp_path: Path,
) -> None:
    profile = team_profile(tmp_path, vehicles=2, seed=SEED, duration=90.0)
    homes = boot_points(load_profile(str(profile)), SEED, [0, 1])
    # vehicle 0 on ArduCopter instance >= 3 (system id >= 4), vehicle 1 on PX4 above it
    a_index = max(sitl.free_index("arducopter"), 3)
    copter = arducopter(index=a_index, speedup=SPEEDUP, home=f"{homes[0]},0", battery_mah=20000)
    pixhawk = px4(index=max(sitl.free_index("px4"), a_index + 1), speedup=SPEEDUP, home=homes[1])
    instances = {0: copter, 1: pixhawk}
    assert all(inst.sysid != i + 1 for i, inst in instances.items())
    fleet_file = tmp_path / "fleet.yaml"
    fleet_file.write_text(
        yaml.safe_dump(
            {
                "vehicles": [
                    {
                        "index": i,
                        "link": inst.companion_url,
                        "system_id": inst.sysid,
                        "autopilot": inst.kind,
                    }
                    for i, inst in instances.items()
                ]
            }
        )
    )
    out = tmp_path / "run"
    observers = {i: Observer(inst.observer_url, inst.sysid) for i, inst in instances.items()}
    fleet = start_fleet("--profile", str(profile), "--vehicles-file", str(fleet_file),
                        "--link-timeout", "120", "--seed", str(SEED), "--out", str(out),
                        "--duration", "90", "--land-wait", "600", "--flight-log-wait", "0", "--quiet",
                        output=tmp_path / "fleet.out")  # fmt: skip
    try:
        code = fleet.wait(timeout=1200)
        traces = {i: o.snapshot() for i, o in observers.items()}
    finally:
        if fleet.poll() is None:
            os.killpg(fleet.pid, signal.SIGKILL)
        for o in observers.values():
            o.close()
    text = (tmp_path / "fleet.out").read_text(errors="replace")
    assert code == 0, text[-3000:]
    assert not (out / "emulator.log").exists()
    polygon = fence_polygon(profile)
    lines = []
    for i, t in sorted(traces.items()):
        f = figures(t, instances[i].kind, polygon)
        lines.append(f.line(i, f"{instances[i].kind}, system {instances[i].sysid}"))
        assert f.armed_ever, lines[-1]
        assert f.outside == 0, lines[-1]
        assert abs(f.layer - (40.0 + 5.0 * i)) <= 2.0, lines[-1]
        assert f.end == "landed, disarmed", lines[-1]
    print("\n" + "\n".join(lines))
    result = json.loads((out / "results.json").read_text())
    assert result["complete"], result["ends"]
    assert result["tnc"] >= 1
    run = json.loads((out / "run.json").read_text())
    assert [v["system_id"] for v in run["team"]] == [copter.sysid, pixhawk.sysid]
