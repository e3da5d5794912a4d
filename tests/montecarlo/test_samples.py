"""Per-run samples: what `run` and `reproduce` write, read back, give their aggregates."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from mdm_core import metrics
from mdm_montecarlo.commands.cli import main
from mdm_montecarlo.commands.result_files import report_provenance
from mdm_montecarlo.engines.runner import run_missions
from mdm_montecarlo.study.samples import read_provenance
from mdm_montecarlo.study.variants import with_method
from mdm_profiles import load_profile

PROVENANCE_FIELDS = {
    "package_version", "git_commit", "git_dirty", "python", "numpy", "numba", "cpu_model",
    "cpu_vector_flags", "seed", "command_line", "wall_s", "cpu_s",
}  # fmt: skip


def test_run_samples_give_its_aggregates_bit_for_bit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["run", "--profile", "paper-fixed", "--method", "MDM:LS+BS", "--runs", "150"]
    assert main([*argv, "--seed", "11", "--workers", "1", "--out", str(tmp_path), "--json"]) == 0
    row = json.loads(capsys.readouterr().out)
    runs = pq.read_table(tmp_path / "samples-runs.parquet").to_pydict()
    direct = run_missions(load_profile("paper-fixed"), runs=150, seed=11)
    ts, capped = direct.ts()
    assert np.array_equal(runs["tnc"], direct.tnc)
    assert np.array_equal(runs["ts_s"], ts)  # exact float equality, not a tolerance
    assert np.array_equal(runs["ts_capped"], capped)
    tnc_sum, ts_sum = metrics.Summary.of(np.array(runs["tnc"])), metrics.Summary.of(ts)
    assert tnc_sum == metrics.Summary.of(direct.tnc)
    assert row["tnc_mean"] == round(tnc_sum.mean, 3)
    assert row["tnc_std"] == round(tnc_sum.std, 3)
    assert row["tnc_ci95"] == [round(tnc_sum.ci_low, 3), round(tnc_sum.ci_high, 3)]
    assert row["ts_mean_s"] == round(ts_sum.mean)
    assert row["capped"] == int(sum(runs["ts_capped"]))
    assert set(runs["seed"]) == {11}
    assert runs["run"] == list(range(150))


def _columns(path: Path) -> dict[str, np.ndarray]:
    return {k: np.array(v) for k, v in pq.read_table(path).to_pydict().items()}


def test_confirmations_are_the_runs_outcomes_with_a_vehicle_each(tmp_path: Path) -> None:
    argv = ["run", "--profile", "paper-fixed-false", "--method", "US", "--runs", "60"]
    assert main([*argv, "--workers", "1", "--out", str(tmp_path), "--no-progress"]) == 0
    runs = _columns(tmp_path / "samples-runs.parquet")
    conf = _columns(tmp_path / "samples-confirmations.parquet")
    n = len(runs["run"])
    assert ((conf["vehicle"] >= 0) & (conf["vehicle"] < runs["n_uav"][0])).all()
    real = ~conf["false_target"]
    counted = np.bincount(conf["run"][real & conf["within_duration"]], minlength=n)
    assert np.array_equal(counted, runs["tnc"])
    false = np.bincount(conf["run"][conf["false_target"]], minlength=n)
    assert np.array_equal(false, runs["false_confirmations"])
    last = np.full(n, -np.inf)
    np.maximum.at(last, conf["run"][real], conf["time_s"][real])
    complete = ~runs["ts_capped"]
    assert complete.any()
    assert np.array_equal(last[complete], runs["ts_s"][complete])
    csv_runs = (tmp_path / "samples-runs.csv").read_text().splitlines()
    assert len(csv_runs) == 1 + n


def test_reproduce_writes_samples_and_a_provenance_block_that_parses(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["reproduce", "--tables", "section3b", "--runs", "20", "--workers", "1"]
    argv += ["--seed", "5", "--out", str(tmp_path), "--no-progress"]
    assert main(argv) == 0
    capsys.readouterr()
    block = report_provenance(tmp_path / "report.md")
    assert set(block) == PROVENANCE_FIELDS
    assert block["seed"] == 5
    assert block["command_line"] == ["mdm-montecarlo", *argv]
    assert json.loads((tmp_path / "provenance.json").read_text()) == block
    assert read_provenance(tmp_path / "samples-runs.parquet") == block
    runs = pq.read_table(tmp_path / "samples-runs.parquet").to_pydict()
    assert sorted(set(runs["method"])) == ["MDM:LS+BS", "US"]
    assert len(runs["run"]) == 40


def test_method_mdm_alone_is_the_profiles_levels(capsys: pytest.CaptureFixture[str]) -> None:
    profile = load_profile("paper-fixed")
    assert with_method(profile, "MDM").policy == with_method(profile, "MDM:LS+BS").policy
    with pytest.raises(ValueError, match="not MDM; name the levels"):
        with_method(with_method(profile, "US"), "MDM")
