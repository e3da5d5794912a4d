"""`mdm-montecarlo compare`: MDM against US, two seeds of one configuration, bad input."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy import stats

from mdm_montecarlo.commands.cli import main
from mdm_montecarlo.study.compare import compare_samples


def _rows(capsys: pytest.CaptureFixture[str]) -> dict[str, dict[str, Any]]:
    lines = capsys.readouterr().out.splitlines()
    return {row["metric"]: row for row in map(json.loads, lines)}


def test_compare_finds_mdm_ahead_of_us_on_fixed_targets(
    capsys: pytest.CaptureFixture[str],
) -> None:
    argv = ["compare", "paper-fixed:US", "paper-fixed:MDM", "--runs", "300", "--workers", "1"]
    assert main([*argv, "--json", "--bootstrap", "2000"]) == 0
    rows = _rows(capsys)
    tnc, ts = rows["T_nc"], rows["T_S"]
    assert tnc["mann_whitney_p"] < 0.01
    assert tnc["welch_p"] < 0.01
    assert tnc["ci95"][0] > 0
    assert tnc["bootstrap_ci95"][0] > 0
    assert tnc["cohens_d"] > 0
    assert ts["mann_whitney_p"] < 0.01
    assert ts["ci95"][1] < 0  # MDM confirms all targets sooner


def test_two_seeds_of_one_configuration_differ_by_nothing_significant(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for seed in ("1", "2"):
        argv = ["run", "--profile", "paper-fixed", "--method", "US", "--runs", "300"]
        assert main([*argv, "--seed", seed, "--workers", "1", "--out", str(tmp_path / seed)]) == 0
    capsys.readouterr()
    assert main(["compare", str(tmp_path / "1"), str(tmp_path / "2"), "--json"]) == 0
    rows = _rows(capsys)
    assert set(rows) == {"T_nc", "T_S"}
    for row in rows.values():
        assert row["n_a"] == row["n_b"] == 300
        assert row["mann_whitney_p"] > 0.05
        low, high = row["ci95"]
        assert low < 0 < high


def test_welch_and_the_rank_test_agree_with_scipy() -> None:
    rng = np.random.default_rng(3)
    a, b = rng.poisson(4.0, 400), rng.poisson(4.4, 500)
    c = compare_samples("T_nc", a, b, resamples=500)
    welch = stats.ttest_ind(b, a, equal_var=False)
    assert c.welch_p == pytest.approx(welch.pvalue, rel=1e-9)
    low, high = welch.confidence_interval(0.95)
    assert c.ci95 == pytest.approx((low, high), rel=1e-9)
    u = stats.mannwhitneyu(b, a, alternative="two-sided")
    assert (c.mann_whitney_u, c.mann_whitney_p) == pytest.approx((u.statistic, u.pvalue))
    assert c.bootstrap_ci95[0] < c.difference < c.bootstrap_ci95[1]


@pytest.mark.parametrize(
    ("a", "b"),
    [
        ([3, 4, 4, 5, 2, 4, 3, 3, 4, 6] * 30, [4, 5, 5, 3, 4, 6, 5, 4, 5, 7] * 25),  # ties
        ([0.31, 2.5, 1.7], [0.2, 3.9]),  # a few values, no ties
        ([1.0, 1.0, 1.0], [1.0, 1.0]),  # one value: p = 1
        ([0.0, 0.0, 0.0], [2.0, 2.0, 2.0, 2.0]),  # two constant samples apart
        (list(range(50)), list(range(50))),  # the same sample
        ([31500.0, 29800.0, 40000.0, 40000.0], [40000.0, 22000.0, 40000.0, 35100.0]),  # caps
    ],
)
def test_the_rank_test_is_scipys_asymptotic_one(a: list[float], b: list[float]) -> None:
    c = compare_samples("T_S", np.array(a), np.array(b), resamples=100)
    u = stats.mannwhitneyu(b, a, alternative="two-sided", method="asymptotic")
    assert c.mann_whitney_u == pytest.approx(float(u.statistic), rel=1e-12)
    assert c.mann_whitney_p == pytest.approx(float(u.pvalue), rel=1e-9, abs=1e-15)


def test_a_folder_of_several_configurations_needs_one_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["reproduce", "--tables", "section3b", "--runs", "20", "--workers", "1"]
    assert main([*argv, "--out", str(tmp_path), "--no-progress"]) == 0
    capsys.readouterr()
    assert main(["compare", str(tmp_path), str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "holds 2 configurations" in err
    config = "fixed US d1=20% uav=1 false=0"
    assert config in err
    other = "fixed MDM:LS+BS d1=20% uav=1 false=0"
    assert main(["compare", f"{tmp_path}#{config}", f"{tmp_path}#{other}", "--json"]) == 0
    assert _rows(capsys)["T_nc"]["n_a"] == 20


@pytest.mark.parametrize(
    ("a", "message"),
    [("no-such-profile:US", "no-such-profile"), ("paper-fixed:XS", "unknown method 'XS'")],
)
def test_a_bad_side_is_refused_before_simulating(
    a: str, message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["compare", "paper-fixed:US", a, "--runs", "100000"]) == 2
    assert message in capsys.readouterr().err
