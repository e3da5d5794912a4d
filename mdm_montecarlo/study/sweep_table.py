"""A sweep's combined table: one row per point, the aggregates computed from its samples."""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mdm_core import metrics
from mdm_montecarlo.study.sweep import SweepAsk

if TYPE_CHECKING:
    import pyarrow as pa


@dataclass(frozen=True)
class PointRow:
    point: int
    values: dict[str, str]
    runs: int
    tnc: metrics.Summary
    ts: metrics.Summary | None
    """None where the runs stop at the mission duration (the swarms)."""
    capped: int | None

    def as_dict(self) -> dict[str, object]:
        return {
            "point": self.point,
            **self.values,
            "runs": self.runs,
            **_summary_columns("tnc", self.tnc),
            **_summary_columns("ts_s", self.ts),
            "capped": self.capped,
        }


def _summary_columns(name: str, s: metrics.Summary | None) -> dict[str, float | None]:
    return {
        f"{name}_mean": None if s is None else s.mean,
        f"{name}_std": None if s is None else s.std,
        f"{name}_ci_low": None if s is None else s.ci_low,
        f"{name}_ci_high": None if s is None else s.ci_high,
    }


def point_rows(ask: SweepAsk, runs: pa.Table) -> list[PointRow]:
    """Mean, standard deviation and 95 % CI of T_nc and T_S per point, from the runs table."""
    cols = {k: np.asarray(v) for k, v in runs.to_pydict().items()}
    rows = []
    for index in dict.fromkeys(cols["point"].tolist()):
        mine = cols["point"] == index
        has_ts = bool(cols["has_ts"][mine].all())
        first = int(np.argmax(mine))
        rows.append(
            PointRow(
                point=int(index),
                values={k: str(cols[k][first]) for k, _ in ask.vary},
                runs=int(mine.sum()),
                tnc=metrics.Summary.of(cols["tnc"][mine]),
                ts=metrics.Summary.of(cols["ts_s"][mine]) if has_ts else None,
                capped=int(cols["ts_capped"][mine].sum()) if has_ts else None,
            )
        )
    return rows


def write_csv(path: Path, rows: list[PointRow]) -> None:
    with path.open("w", newline="", encoding="utf-8") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0].as_dict()))
        writer.writeheader()
        for row in rows:
            writer.writerow(row.as_dict())


def format_rows(ask: SweepAsk, rows: list[PointRow]) -> str:
    """A Markdown table: the varied values, then T_nc and T_S with their 95 % intervals."""
    keys = [k for k, _ in ask.vary]
    lines = [
        "| " + " | ".join(keys) + " | runs | T_nc mean ± std | T_nc 95 % CI |"
        " T_S s mean ± std | T_S 95 % CI | capped |",
        "|" + "---|" * (len(keys) + 6),
    ]
    for r in rows:
        ts = (
            " |"  # two empty cells
            if r.ts is None
            else (f"{r.ts.mean:.0f} ± {r.ts.std:.0f} | [{r.ts.ci_low:.0f}, {r.ts.ci_high:.0f}]")
        )
        lines.append(
            "| " + " | ".join(r.values[k] for k in keys) + f" | {r.runs} | "
            f"{r.tnc.mean:.3f} ± {r.tnc.std:.3f} | [{r.tnc.ci_low:.3f}, {r.tnc.ci_high:.3f}] | "
            f"{ts} | {'' if r.capped is None else r.capped} |"
        )
    return "\n".join(lines)
