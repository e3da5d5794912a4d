"""`mdm-montecarlo plan`: its probability against direct runs of the same configurations,
and the input it refuses (exit 2, naming what)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from mdm_montecarlo.commands.cli import main
from mdm_montecarlo.engines.runner import run_many, run_missions
from mdm_montecarlo.study.team_plan import PlanAsk, plan_row, profiles
from mdm_profiles import builtin_profile


def test_plan_probability_matches_direct_runs() -> None:
    """field-duebendorf, 15 min: plan's P(all real targets confirmed) for LM2 at 2 and MDM at
    4 vehicles (both near 0.4-0.5, where the standard error is largest) against runs of the
    same profiles with another seed, counted here from the confirmation times: within 3.5
    standard errors of the difference."""
    ask = PlanAsk(builtin_profile("field-duebendorf"), (2, 4), 15.0, ("LM2", "MDM"), 0.9)
    configs = [c for c in profiles(ask) if (c[0], c[1]) in {("LM2", 2), ("MDM", 4)}]
    planned = run_many([c[2] for c in configs], runs=400, seed=1, workers=1)
    for (method, n, profile), result in zip(configs, planned, strict=True):
        row = plan_row(method, n, result)
        direct = run_missions(profile, runs=400, seed=2, workers=1)
        real = np.array([not t.false_target for t in profile.targets])
        hit = (direct.team_times[:, real] <= 15 * 60).all(axis=1).mean()
        se = math.sqrt(row.p_all_se**2 + hit * (1 - hit) / 400)
        assert 0.2 < row.p_all < 0.8, row
        assert abs(row.p_all - hit) <= 3.5 * se, (method, n, row.p_all, hit, se)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--profile", "paper-fixed", "--teams", "4", "--endurance", "30"], "no site fence"),
        (
            ["--profile", "field-duebendorf", "--teams", "4", "--endurance", "3"],
            "below the transit",
        ),
        (
            ["--profile", "field-duebendorf", "--teams", "4,18", "--endurance", "15"],
            "more than profile 'field-duebendorf' can start",
        ),
        (
            [
                "--profile",
                "field-duebendorf",
                "--teams",
                "4",
                "--endurance",
                "15",
                "--methods",
                "XS",
            ],
            "unknown method 'XS'",
        ),
    ],
)
def test_bad_input_is_refused(
    args: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["plan", *args, "--runs", "10", "--out", str(tmp_path / "plan")])
    assert code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "plan" / "plan.csv").exists()


def test_plan_writes_table_csv_and_plot(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "plan"
    code = main(
        [
            "plan",
            "--profile",
            "field-duebendorf",
            "--teams",
            "2,6",
            "--endurance",
            "15",
            "--methods",
            "LM1,MDM",
            "--runs",
            "100",
            "--workers",
            "1",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    text = capsys.readouterr().out
    assert "| LM1 | 6 | 1.000 |" in text  # three 6-vehicle cells swept within 15 min every run
    assert "LM1: smallest team with P >= 0.9: 6 vehicles" in text
    assert (out / "plan.png").stat().st_size > 10_000
    assert len((out / "plan.csv").read_text().splitlines()) == 5


def test_plan_on_dask_gives_the_local_plan(tmp_path: Path) -> None:
    """`--scheduler` (Dask, as `run`): a local cluster of two worker processes writes the
    plan.csv one local process writes, number for number."""
    from distributed import LocalCluster

    argv = ["plan", "--profile", "field-duebendorf", "--teams", "2,4", "--endurance", "15",
            "--methods", "LM2,MDM", "--runs", "40", "--no-progress"]  # fmt: skip
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:  # type: ignore[no-untyped-call]
        dask = main([*argv, "--scheduler", cluster.scheduler_address, "--out", str(tmp_path / "d")])
    assert dask == 0
    assert main([*argv, "--workers", "1", "--out", str(tmp_path / "one")]) == 0
    table = (tmp_path / "one" / "plan.csv").read_text()
    assert (tmp_path / "d" / "plan.csv").read_text() == table
    assert len(table.splitlines()) == 5
