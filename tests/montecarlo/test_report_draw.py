"""The report's figures drawn while the other result files are written: each waits for the
other, and an error of either is raised."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from mdm_montecarlo.study.report import _draw


def _fails(path: str) -> None:
    raise RuntimeError(f"cannot draw {path}")


def _draws(path: str) -> None:
    Path(path).write_text("figure", encoding="utf-8")


@pytest.mark.parametrize("workers", [1, 2])
def test_a_failing_plot_leaves_the_other_files_written_whole(tmp_path: Path, workers: int) -> None:
    def samples() -> None:
        time.sleep(0.3)  # still writing when the first plot fails
        (tmp_path / "samples.csv").write_text("whole", encoding="utf-8")

    plots = [(_fails, (str(tmp_path / "a.png"),)), (_draws, (str(tmp_path / "b.png"),))]
    with pytest.raises(RuntimeError, match="cannot draw"):
        _draw(plots, workers, samples)
    assert (tmp_path / "samples.csv").read_text(encoding="utf-8") == "whole"


@pytest.mark.parametrize("workers", [1, 2])
def test_an_error_writing_the_other_files_is_raised_once_the_plots_are_drawn(
    tmp_path: Path, workers: int
) -> None:
    def samples() -> None:
        raise OSError("disk full")

    pngs = [tmp_path / f"{k}.png" for k in range(3)]
    with pytest.raises(OSError, match="disk full"):
        _draw([(_draws, (str(p),)) for p in pngs], workers, samples)
    assert all(p.read_text(encoding="utf-8") == "figure" for p in pngs)
