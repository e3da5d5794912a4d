"""A lawnmower vehicle whose cell has no lane inside the guidance fence is refused before
anything starts (exit 2, naming the vehicle), not flown along the fence's edge: by `companion
run` for its vehicle, by `companion fleet` for the whole team."""

from __future__ import annotations

from pathlib import Path

import pytest

from companion.cli import main
from companion.fence_from_profile import profile_frame
from mdm_core.search.lawnmower_profile import team_plan
from mdm_core.world.scenario import Scenario
from mdm_montecarlo.study.variants import with_method
from mdm_profiles import builtin_profile, write_profile
from mdm_profiles.schema import GeoPoint

SEED = 0


@pytest.mark.parametrize("command", ["run", "fleet"])
def test_a_cell_outside_the_fence_is_refused(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    base = with_method(builtin_profile("field-duebendorf"), "LM1")
    frame = profile_frame(base)
    south = [(60.0, 60.0), (500.0, 60.0), (500.0, 1940.0), (60.0, 1940.0)]  # the south half
    fence = [
        GeoPoint(lat=la, lon=lo) for la, lo, _ in (frame.to_geodetic(n, e, 0.0) for n, e in south)
    ]
    assert base.site is not None
    profile = base.model_copy(update={"site": base.site.model_copy(update={"geofence": fence})})
    starts, _ = Scenario.from_profile(profile).live_run(SEED, 4, profile.fleet.start)
    regions = team_plan(profile, starts).regions
    north = next(i for i in range(4) if regions[i, 0, 0] >= 600.0)  # a cell north of it
    path = tmp_path / "south-fence.yaml"
    write_profile(profile, path)
    argv = ["run", "--profile", str(path), "--vehicle", str(north), "--seed", str(SEED),
            "--connect", "udpin:127.0.0.1:1", "--log-dir", str(tmp_path / "log")]  # fmt: skip
    if command == "fleet":  # the whole team checked before a process starts
        argv = [
            "fleet",
            "--profile",
            str(path),
            "--seed",
            str(SEED),
            "--out",
            str(tmp_path / "log"),
        ]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"vehicle {north}: no lane of this vehicle's cell lies inside the guidance" in err
    assert not (tmp_path / "log" / f"mission-{north}.jsonl").exists()
    assert not (tmp_path / "log" / "run.json").exists()
