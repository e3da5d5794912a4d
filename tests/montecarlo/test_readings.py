"""--reading NAME of run, reproduce and sweep: the readings as named data, listed by
`--reading help`, refused by name otherwise, and flown as their overrides."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from mdm_montecarlo.commands.cli import main
from mdm_montecarlo.study.cases import VARIANTS, Case
from mdm_montecarlo.study.readings import READINGS, reading_cases, with_reading
from mdm_profiles import ProfileError, builtin_profile

COMMANDS = (
    ["run"],
    ["reproduce", "--tables", "simtable1"],
    ["sweep", "--profile", "paper-fixed", "--vary", "mission.duration=500"],
)


@pytest.mark.parametrize("command", COMMANDS, ids=lambda c: c[0])
def test_reading_help_lists_every_reading_and_its_overrides(
    command: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as stop:  # before --profile is found missing
        main([command[0], "--reading", "help"])
    assert stop.value.code == 0
    out = capsys.readouterr().out
    for name, reading in READINGS.items():
        assert f"  {name}: " in out
        for keys in reading.choices.values():
            assert " ".join(VARIANTS[keys[0]][1]) in out


@pytest.mark.parametrize("command", COMMANDS, ids=lambda c: c[0])
def test_an_unknown_reading_exits_2_listing_the_readings(
    command: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = [*command, "--reading", "loosest", "--out", str(tmp_path / "out"), "--runs", "2"]
    if command[0] == "run":
        argv += ["--profile", "paper-fixed"]
    assert main([*argv, "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "unknown reading 'loosest'" in err
    assert "readings: default, closest" in err
    assert not (tmp_path / "out").exists()


def _row(argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> dict[str, object]:
    base = ["run", "--profile", "paper-dynamic", "--method", "US", "--runs", "24", "--json"]
    assert main([*base, "--workers", "1", "--out", str(tmp_path / str(len(argv))), *argv]) == 0
    row: dict[str, object] = json.loads(capsys.readouterr().out)
    return row


def test_run_with_the_closest_reading_flies_its_dynamic_choice(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """On moving targets 'closest' is the free walk with departures counted: the same row as
    those two overrides by hand, and another T_S than the default reading's."""
    closest = _row(["--reading", "closest"], tmp_path, capsys)
    by_hand = ["--set", "target_motion.boundary=free", "--set", "mission.ts_rule=confirmed_or_gone"]
    by_hand += ["--set", "policy.redetection=renew"]
    assert closest == _row(by_hand, tmp_path, capsys)
    default = _row(["--reading", "default", "--no-progress"], tmp_path, capsys)
    assert float(closest["ts_mean_s"]) < float(default["ts_mean_s"])  # type: ignore[arg-type]


def test_a_profile_that_cannot_take_the_reading_is_refused_naming_it() -> None:
    popup = builtin_profile("paper-popup")
    three = popup.model_copy(update={"targets": popup.targets[:3]})
    with pytest.raises(ProfileError, match=r"--reading closest: its popup choice"):
        with_reading(three, "closest")
    assert with_reading(three, "default") == three


def test_sweep_records_the_readings_overrides_before_its_own(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "sweep"
    argv = ["sweep", "--profile", "paper-dynamic", "--method", "US", "--reading", "closest"]
    argv += ["--vary", "mission.duration=300", "--set", "mission.ts_cap=300", "--runs", "2"]
    assert main([*argv, "--out", str(out), "--workers", "1", "--no-progress"]) == 0
    asked = json.loads((out / "sweep.json").read_text())
    assert asked["overrides"] == [*VARIANTS["targets_leave_renew"][1], "mission.ts_cap=300"]


def test_reading_cases_put_the_variant_under_the_default_key() -> None:
    dynamic = Case("dynamic", "US", 20.0, 12, 0)
    fixed = Case("fixed", "US", 20.0, 12, 0)
    results = {dynamic: "bounce", replace(dynamic, variant="targets_leave"): "leave", fixed: "f"}
    assert reading_cases(results, "closest") == {dynamic: "leave", fixed: "f"}
    assert reading_cases(results, "default") == {dynamic: "bounce", fixed: "f"}
    # MDM has the renewed rows too: its first choice wins where it was flown.
    mdm = Case("dynamic", "MDM:LS+BS", 20.0, 12, 0)
    results[mdm] = "bounce"
    results[replace(mdm, variant="targets_leave")] = "leave"
    results[replace(mdm, variant="targets_leave_renew")] = "leave, renewed"
    assert reading_cases(results, "closest")[mdm] == "leave, renewed"
