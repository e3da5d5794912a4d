"""`mdm-montecarlo sweep`: Ctrl-C and the same command again give the table of one straight
run; any number of workers or Dask give the same numbers; bad fields refused before work."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from distributed import LocalCluster

from mdm_core import metrics
from mdm_montecarlo.commands.cli import main
from mdm_montecarlo.commands.result_files import report_provenance
from mdm_montecarlo.study.sweep import SweepAsk
from mdm_montecarlo.study.sweep_table import PointRow, format_rows
from tests.waiting import wait_until

EXE = [sys.executable, "-m", "mdm_montecarlo.commands.cli"]
SWEEP = [
    "sweep", "--profile", "paper-fixed", "--method", "MDM", "--seed", "9",
    "--vary", "policy.levels.1.index.kappa=90,180,360", "--vary", "policy.levels.0.step=2000,4000",
]  # fmt: skip


def _sigint_as_from_a_terminal() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)  # see test_cli_interrupt.py


def _points_done(folder: Path) -> int:
    return len(list((folder / "points").glob("*-samples-runs.parquet")))


def _samples(folder: Path) -> dict[str, list[object]]:
    table: dict[str, list[object]] = pq.read_table(folder / "samples-runs.parquet").to_pydict()
    return table


def test_a_sweep_stopped_by_sigint_and_resumed_gives_the_straight_table(tmp_path: Path) -> None:
    straight, resumed = tmp_path / "straight", tmp_path / "resumed"
    argv = [*SWEEP, "--runs", "400", "--no-progress"]
    assert main([*argv, "--workers", "1", "--out", str(straight)]) == 0
    proc = subprocess.Popen(
        [*EXE, *argv, "--workers", "2", "--out", str(resumed)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
        preexec_fn=_sigint_as_from_a_terminal,  # noqa: PLW1509 - one signal call in the child
    )  # fmt: skip
    try:
        wait_until(lambda: _points_done(resumed) or proc.poll() is not None, 300, "a point")
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 130, err.decode()[-2000:]
    kept = _points_done(resumed)
    assert 1 <= kept < 6
    assert f"{kept} of 6 points done" in err.decode()
    assert not (resumed / "results.csv").exists()
    again = subprocess.run(
        [*EXE, *argv, "--workers", "2", "--out", str(resumed)],
        capture_output=True, text=True, timeout=600, check=False,
    )  # fmt: skip
    assert again.returncode == 0, again.stderr[-2000:]
    assert f"resuming {resumed}: {kept} of 6 points already done" in again.stderr
    assert (resumed / "results.csv").read_text() == (straight / "results.csv").read_text()
    assert _samples(resumed) == _samples(straight)
    assert report_provenance(resumed / "report.md")["seed"] == 9
    for png in ("sweep-tnc.png", "sweep-ts.png"):
        assert (resumed / png).stat().st_size > 10_000


@pytest.fixture(scope="module")
def cluster() -> Iterator[LocalCluster]:
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as c:  # type: ignore[no-untyped-call]
        yield c


def test_the_same_seed_gives_the_same_table_on_any_workers_or_dask(
    tmp_path: Path, cluster: LocalCluster, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = [*SWEEP, "--runs", "60", "--no-progress", "--json"]
    tables = []
    for name, how in [
        ("one", ["--workers", "1"]),
        ("two", ["--workers", "2"]),
        ("dask", ["--scheduler", cluster.scheduler_address]),
    ]:
        assert main([*argv, *how, "--out", str(tmp_path / name)]) == 0
        rows = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
        assert len(rows) == 6
        tables.append(((tmp_path / name / "results.csv").read_text(), rows))
    assert tables[0] == tables[1] == tables[2]
    # Not one number six times: the parameters change the outcome.
    assert len({row["tnc_mean"] for row in tables[0][1]}) > 1


def test_another_sweep_in_the_same_folder_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = [*SWEEP, "--runs", "20", "--workers", "1", "--no-progress", "--out", str(tmp_path)]
    assert main(argv) == 0
    capsys.readouterr()
    assert main([*argv[:-2], "--seed", "10", "--out", str(tmp_path)]) == 2
    assert "holds another sweep" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("vary", "message"),
    [
        ("policy.nonsense=1,2", "policy.nonsense: unknown key"),
        ("policy.levels.1.index.kappa=100,abc", "policy.levels.1.index.kappa=abc"),
        ("policy.levels.7.step=1,2", "policy.levels has 2 entries"),
        ("policy.levels.0.step=1,,2", "an empty value"),
        ("policy.levels.0.step", "expected dotted.path=V1,V2"),
    ],
)
def test_bad_fields_and_values_are_refused_before_any_work(
    vary: str, message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "sweep"
    argv = ["sweep", "--profile", "paper-fixed", "--vary", vary, "--runs", "100000"]
    assert main([*argv, "--out", str(out)]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_a_point_without_t_s_keeps_the_tables_columns() -> None:
    ask = SweepAsk("paper-fixed", "PSO", [], [("fleet.vehicles", ["6"])], 3, 1)
    tnc = metrics.Summary.of(np.array([1, 2, 3]))
    lines = format_rows(ask, [PointRow(0, {"fleet.vehicles": "6"}, 3, tnc, None, None)])
    head, _, row = lines.splitlines()
    assert row.count("|") == head.count("|")
