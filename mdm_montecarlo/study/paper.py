"""The paper's published numbers (section IV), shipped as data/paper_tables.csv."""

from __future__ import annotations

import csv
from dataclasses import dataclass
from importlib import resources


@dataclass(frozen=True)
class PaperRow:
    """One row of a section IV table, as printed in the paper."""

    table: str
    scenario: str
    method: str
    level1: str
    level2: str
    delta1_pct_L: float | None
    n_uav: int
    n_targets: int
    n_false: int
    tnc_mean: float
    tnc_std: float
    ts_mean_s: float | None
    ts_std_s: float | None
    aise_pct: float | None
    aisc_pct: float | None


def _num(text: str) -> float | None:
    return float(text) if text.strip() else None


def paper_rows() -> list[PaperRow]:
    """Every row of paper_tables.csv."""
    path = resources.files("mdm_montecarlo.study") / "data" / "paper_tables.csv"
    with path.open(encoding="utf-8") as fh:
        return [
            PaperRow(
                table=r["table"],
                scenario=r["scenario"],
                method=r["method"],
                level1=r["level1"],
                level2=r["level2"],
                delta1_pct_L=_num(r["delta1_pct_L"]),
                n_uav=int(r["n_uav"]),
                n_targets=int(r["n_targets"]),
                n_false=int(r["n_false"]),
                tnc_mean=float(r["tnc_mean"]),
                tnc_std=float(r["tnc_std"]),
                ts_mean_s=_num(r["ts_mean_s"]),
                ts_std_s=_num(r["ts_std_s"]),
                aise_pct=_num(r["aise_pct"]),
                aisc_pct=_num(r["aisc_pct"]),
            )
            for r in csv.DictReader(fh)
        ]
