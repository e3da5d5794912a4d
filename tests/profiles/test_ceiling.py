"""The ceiling (site.max_altitude, 120 m above take-off by default): a team whose altitude layers
do not all fit under it is refused before anything connects or arms, exit 2, saying how many
vehicles fit with the profile's spacing (fleet.altitude_step); the built-in profiles fit."""

from __future__ import annotations

from pathlib import Path

import pytest

from companion.cli import main
from mdm_profiles import builtin_profile, builtin_profiles, load_profile
from mdm_profiles.ceiling import CeilingError, ceiling, check_ceiling, vehicles_that_fit
from tests.fleet_cli import run_fleet_cli
from tests.profile_files import profile_with, write_profile_with

HUNDRED = {"vehicles": 100, "altitude": 30.0, "altitude_step": 5.0}


def test_a_hundred_vehicles_at_five_metres_do_not_fit_under_120_m() -> None:
    profile = profile_with("tall", fleet=HUNDRED)
    assert profile.site is None
    assert ceiling(profile) == 120.0
    assert vehicles_that_fit(profile) == 19  # 30, 35, ... 120 m
    check_ceiling(profile, 19)
    with pytest.raises(CeilingError) as refused:
        check_ceiling(profile, 20)
    assert str(refused.value) == (
        "profile 'tall': 20 vehicles fly layers up to 125 m (fleet.altitude 30 m + 19 x "
        "fleet.altitude_step 5 m), above the default ceiling 120 m: 19 vehicles fit with that "
        "spacing"
    )


def test_the_sites_ceiling_and_spacing_decide() -> None:
    field = builtin_profile("field-duebendorf")
    assert field.site is not None
    low = field.model_copy(update={"site": field.site.model_copy(update={"max_altitude": 52.0})})
    assert vehicles_that_fit(low) == 3  # 40, 45, 50 m
    with pytest.raises(CeilingError, match=r"above site.max_altitude 52 m: 3 vehicles fit"):
        check_ceiling(low, 4)
    tight = low.model_copy(update={"fleet": low.fleet.model_copy(update={"altitude_step": 2.0})})
    assert vehicles_that_fit(tight) == 7  # 40 .. 52 m
    check_ceiling(tight, 7)
    over = low.model_copy(update={"fleet": low.fleet.model_copy(update={"altitude": 60.0})})
    assert vehicles_that_fit(over) == 0


@pytest.mark.parametrize("name", builtin_profiles())
def test_the_builtin_profiles_fit(name: str) -> None:
    profile = builtin_profile(name)
    check_ceiling(profile, profile.fleet.vehicles)


def test_companion_run_refuses_the_team_before_connecting(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = write_profile_with(tmp_path / "tall.yaml", "tall", fleet=HUNDRED)
    assert load_profile(path).fleet.vehicles == 100
    # a TCP address nobody listens on: a run that got as far as connecting would retry it
    status = main(["run", "--profile", str(path), "--vehicle", "0", "--connect",
                   "tcp:127.0.0.1:9", "--log-dir", str(tmp_path / "logs")])  # fmt: skip
    assert status == 2
    err = capsys.readouterr().err
    assert "100 vehicles fly layers up to 525 m" in err, err
    assert "19 vehicles fit" in err, err
    assert not (tmp_path / "logs").exists()


@pytest.mark.timeout(60)
def test_companion_fleet_refuses_the_team_before_anything_starts(tmp_path: Path) -> None:
    path = write_profile_with(tmp_path / "tall.yaml", "tall", fleet=HUNDRED)
    out = tmp_path / "run"
    done = run_fleet_cli("--profile", str(path), "--vehicles", "30", "--out", str(out))
    assert done.returncode == 2, done.stdout + done.stderr
    assert "--vehicles 30: profile 'tall': 30 vehicles fly layers up to 175 m" in done.stderr
    assert "19 vehicles fit with that spacing" in done.stderr
    assert not out.exists()
