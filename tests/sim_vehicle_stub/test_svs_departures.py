"""Targets of a free walk leave the area in the emulator as in the engine: the `sim-vehicle`
command logs one ``target_gone`` per target, at the departure ``TargetTracks.departures``
solves on the same seed's path, and the target is outside the area after it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from mdm_core.world import Scenario
from mdm_profiles import load_profile
from tests.emulator_harness import free_udp_base
from tests.profile_files import write_profile_with

SEED = 5
TICK = 0.1
"""The emulator's sensor tick (10 Hz telemetry): a departure is logged at the first after it."""


def _free_walk_profile(folder: Path, boundary: str) -> Path:
    """Three targets drifting 7.5 m/s per axis towards north-east on a 3 km square."""
    return write_profile_with(
        folder / f"{boundary}.yaml",
        "departures",
        fleet={"vehicles": 2},
        targets=[
            {"north": 2000.0, "east": 2000.0},
            {"north": 500.0, "east": 900.0},
            {"north": 600.0, "east": 2400.0, "false_target": True},
        ],
        target_motion={"speed": 10.0, "low": 0.5, "high": 1.0, "boundary": boundary},
    )


def _events(folder: Path, profile: Path, sim_seconds: float) -> list[dict[str, Any]]:
    """The event log of `sim-vehicle` run flat out for ``sim_seconds``."""
    events = folder / f"{profile.stem}-events.jsonl"
    base = free_udp_base(2, gap=80)
    exe = Path(sys.executable).parent / "sim-vehicle"
    cmd = [
        str(exe), "--profile", str(profile), "--seed", str(SEED), "--speedup", "0",
        "--base-port", str(base), "--bind-port-base", str(base + 80),
        "--duration", str(sim_seconds), "--events", str(events), "--log-level", "WARNING",
    ]  # fmt: skip
    subprocess.run(cmd, check=True, timeout=120)
    return [json.loads(line) for line in events.read_text().splitlines()]


@pytest.mark.timeout(150)
def test_the_emulator_logs_each_departure_the_engine_solves(tmp_path: Path) -> None:
    path = _free_walk_profile(tmp_path, "free")
    log = _events(tmp_path, path, 500.0)
    gone = {int(e["target"]): e for e in log if e["event"] == "target_gone"}
    profile = load_profile(str(path))
    scenario = Scenario.from_profile(profile)
    _, tracks = scenario.live_run(SEED, 2, profile.fleet.start)
    solved = tracks.departures(500.0)[0]
    # every target drifts out within 500 s (the farthest has 2500 m to go at 7.5 m/s)
    assert np.isfinite(solved).all()
    assert sorted(gone) == [0, 1, 2]
    for k, event in gone.items():
        left = float(event["left_at"])
        assert left == pytest.approx(solved[k], abs=1e-9)
        assert left <= float(event["t"]) <= left + TICK + 1e-6
        assert event["false_target"] is (k == 2)
        # logged where the path crosses the wall, and the emulator's target is outside after
        wall = np.array([event["north"], event["east"]], dtype=float)
        assert np.isclose(wall, 3000.0).any()
        after = tracks.positions(np.zeros(1, dtype=np.intp), np.array([left + 1.0]))[0, k]
        assert not scenario.area.contains(after)


@pytest.mark.timeout(150)
def test_a_bounded_walk_logs_no_departure(tmp_path: Path) -> None:
    log = _events(tmp_path, _free_walk_profile(tmp_path, "bounce"), 500.0)
    assert not [e for e in log if e["event"] == "target_gone"]
    assert sum(e["event"] == "target_appeared" for e in log) == 3
