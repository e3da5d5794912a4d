"""mdm-montecarlo end to end: JSON rows with the paper's column names, report files, --set, errors."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest

from mdm_montecarlo.commands.cli import main

PAPER_COLUMNS = ("table", "scenario", "method", "level1", "level2", "tnc_mean", "tnc_std")


def _json_rows(capsys: pytest.CaptureFixture[str]) -> list[dict[str, object]]:
    out = capsys.readouterr().out
    return [json.loads(line) for line in out.splitlines() if line.strip()]


def test_run_json_row_has_paper_columns_runs_and_capped(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["run", "--profile", "paper-fixed", "--method", "US", "--runs", "12"]
    assert main([*argv, "--out", str(tmp_path / "table")]) == 0
    capsys.readouterr()
    assert main([*argv, "--out", str(tmp_path / "json"), "--json"]) == 0
    (row,) = _json_rows(capsys)
    for column in (*PAPER_COLUMNS, "ts_mean_s", "ts_std_s", "runs", "capped"):
        assert column in row, column
    assert row["method"] == "US"
    assert row["runs"] == 12
    assert 0 <= float(row["tnc_mean"]) <= 10  # type: ignore[arg-type]


def test_reproduce_applies_set_to_every_row_and_writes_the_report(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    args = ["reproduce", "--tables", "simtable4", "--runs", "12", "--workers", "1", "--json"]
    assert main([*args, "--out", str(tmp_path / "plain")]) == 0
    plain = _json_rows(capsys)
    levy = [*args, "--out", str(tmp_path / "levy"), "--set", "policy.levels.0.step_law=levy"]
    assert main(levy) == 0
    changed = _json_rows(capsys)
    assert len(plain) == len(changed) == 18  # nine MDM rows, each with its renewed row
    # Levy step lengths draw other waypoints: the same seed gives other missions.
    assert [r["tnc_mean"] for r in plain] != [r["tnc_mean"] for r in changed]
    report = (tmp_path / "levy" / "report.md").read_text()
    assert "Overrides: policy.levels.0.step_law=levy." in report
    assert "Overrides" not in (tmp_path / "plain" / "report.md").read_text()
    with (tmp_path / "levy" / "results.csv").open() as f:
        assert len(list(csv.DictReader(f))) == 18
    assert list((tmp_path / "levy").glob("*.png"))


def test_swarm_rows_have_no_completion_time(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Runs stopped at the mission duration (as reproduce does for PSO) have no T_S, not
    # "every run capped".
    argv = ["run", "--profile", "paper-fixed", "--method", "PSO", "--runs", "8", "--json"]
    argv += ["--out", str(tmp_path)]
    assert main([*argv, "--set", "mission.ts_cap=1000"]) == 0
    (row,) = _json_rows(capsys)
    assert (row["ts_mean_s"], row["ts_std_s"], row["capped"], row["aisc_pct"]) == (None,) * 4
    assert row["method"] == "PSO"
    assert 0 < float(row["peer_follow_pct"]) <= 100  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["run", "--profile", "paper-fixed", "--method", "XS"], "unknown method 'XS'"),
        (["run", "--profile", "no-such-profile"], "no-such-profile"),
        (
            ["reproduce", "--tables", "simtable4", "--set", "policy.levels.0.step_law=bogus"],
            "policy.levels.0.step_law",
        ),
        (["reproduce", "--tables", "simtable99"], "unknown table"),
    ],
)
def test_bad_input_exits_2_naming_the_problem(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    out = ["--out", str(tmp_path)] if argv[0] == "reproduce" else []
    assert main([*argv, *out, "--runs", "2", "--no-progress"]) == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize("flag", ["--workers", "--runs"])
@pytest.mark.parametrize("value", ["0", "-3", "two"])
def test_workers_and_runs_below_one_are_refused(
    flag: str, value: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["run", "--profile", "paper-fixed", flag, value])
    assert exit_info.value.code == 2
    assert f"argument {flag}" in capsys.readouterr().err


def test_unwritable_out_is_refused_before_any_simulation(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # A regular file where the report folder's parent should be: mkdir fails even as root.
    blocker = tmp_path / "file"
    blocker.write_text("")
    out = blocker / "report"
    # 10^6 runs per row would take minutes: returning at once shows nothing was simulated.
    argv = ["reproduce", "--tables", "simtable1", "--runs", "1000000", "--no-progress"]
    assert main([*argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"--out {out}: not a writable folder" in err
    assert "Traceback" not in err


def test_matplotlib_and_scipy_special_wait_until_the_workers_start() -> None:
    """reproduce imports them while the simulation workers run (cli._import_report); numba
    imports the top-level scipy package only."""
    code = "import sys, mdm_montecarlo.commands.cli; print({'matplotlib', 'scipy.special'} & set(sys.modules))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "set()"
