"""A fleet run (emulator + three companions) with targets that leave the area, scored under
``mission.ts_rule: confirmed_or_gone``: the fleet's departures are those ``TargetTracks``
solves for the same seed, and T_S is the latest, over the real targets, of the earlier of the
first confirmation and the departure."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mdm_core.world import Scenario
from mdm_ground.fleet.runner import FleetOptions, run_fleet
from mdm_profiles import load_profile
from tests.profile_files import sensors, write_profile_with

pytestmark = pytest.mark.usefixtures("fleet_processes")

SEED = 4
TICK = 0.1
"""The emulator's sensor tick: the run's last departure is known if the run lasted a tick
past it."""


def _profile(folder: Path) -> Path:
    """Three vehicles on a 3 km square, the paper's walk free to leave it (2 m/s per axis to the
    north-east): T1 from the middle leaves 750 s after boot, T2 near the corner 73 s after boot;
    with this seed a vehicle starts by T2 and confirms it as its search begins."""
    return write_profile_with(
        folder / "gone.yaml",
        "fleet-gone",
        fleet={"vehicles": 3},
        sensors=sensors(1000.0, 300.0),
        targets=[
            {"north": 1500.0, "east": 1500.0},
            {"north": 2850.0, "east": 2700.0},
            {"north": 600.0, "east": 2400.0, "false_target": True},
        ],
        target_motion={"boundary": "free"},
        mission={"duration": 800.0, "ts_cap": 5000.0, "ts_rule": "confirmed_or_gone"},
    )


@pytest.mark.timeout(300)
def test_the_fleet_scores_departures_as_the_engine_solves_them(tmp_path: Path) -> None:
    path = _profile(tmp_path)
    out = tmp_path / "run"
    result = run_fleet(
        FleetOptions(profile=str(path), out=out, duration=800.0, seed=SEED, wall_limit=200)
    )
    assert result.complete, result.ends
    profile = load_profile(str(path))
    _, tracks = Scenario.from_profile(profile).live_run(SEED, 3, profile.fleet.start)
    solved = tracks.departures(result.sim_time - TICK)[0]
    # every target leaves while the run lasts, at the time the engine's solver gives
    assert np.isfinite(solved).all()
    np.testing.assert_allclose(result.departures, solved, rtol=0, atol=1e-6)
    assert result.search_start is not None
    real = [not t.false_target for t in profile.targets]
    counted = [
        min(result.first_confirmation[k], max(result.departures[k] - result.search_start, 0.0))
        for k in range(len(real))
        if real[k]
    ]
    assert not result.ts_capped
    assert result.ts == pytest.approx(max(counted), abs=1e-9)
    gone = sum(
        1
        for k in range(len(real))
        if real[k] and result.departures[k] - result.search_start < result.first_confirmation[k]
    )
    assert (result.ts_gone, result.ts_confirmed) == (gone, 2 - gone)
    assert result.first_confirmation[1] < result.departures[1] - result.search_start
    written = json.loads((out / "results.json").read_text())
    assert written["departures"] == result.departures
    assert (written["ts_rule"], written["ts_gone"]) == ("confirmed_or_gone", gone)
