"""Measured table rows beside the paper's, with AISE/AISC and the tolerance verdicts."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from mdm_core import metrics
from mdm_montecarlo.engines.runner import MissionResults
from mdm_montecarlo.study.cases import TNC_TOLERANCE, TS_TOLERANCE, VARIANTS, Case, Row
from mdm_montecarlo.study.samples import run_outcomes


@dataclass(frozen=True)
class MeasuredRow:
    """Columns of paper_tables.csv, then runs/capped, then the paper's figures and verdicts."""

    table: str
    scenario: str
    method: str
    level1: str
    level2: str
    delta1_pct_L: float
    n_uav: int
    n_targets: int
    n_false: int
    tnc_mean: float
    tnc_std: float
    ts_mean_s: float | None
    ts_std_s: float | None
    """None where the method is simulated only up to the mission duration (the swarms)."""
    aise_pct: float | None
    aisc_pct: float | None
    runs: int
    capped: int | None
    tnc_ci95: tuple[float, float]
    paper_tnc_mean: float | None
    paper_ts_mean_s: float | None
    tnc_within: bool | None
    ts_within: bool | None
    peer_follow_pct: float | None = None
    """Swarm rows: per cent of particle-iterations that followed a best heard from a peer."""
    variant: str = ""
    """Label of a documented variant of the defaults (study.VARIANTS), '' for the defaults."""

    def as_dict(self) -> dict[str, object]:
        return asdict(self)


def _within(value: float, paper: float | None, tolerance: float) -> bool | None:
    if paper is None:
        return None
    return abs(value - paper) <= tolerance * abs(paper)


def _rounded(pct: float | None) -> float | None:
    return None if pct is None else round(pct, 1)


def _pct(share: float | None) -> float | None:
    return None if share is None else round(100.0 * share, 1)


def measured_rows(rows: list[Row], results: dict[Case, MissionResults]) -> list[MeasuredRow]:
    """One MeasuredRow per study row; AISE/AISC of single-sensor rows against their table's MDM."""
    stats: dict[Case, tuple[metrics.Summary, metrics.Summary, int]] = {}
    for case, res in results.items():
        runs = run_outcomes(res)  # the per-run samples the report writes
        stats[case] = (
            metrics.Summary.of(runs.tnc),
            metrics.Summary.of(np.empty(0) if runs.ts is None else runs.ts),
            0 if runs.ts_capped is None else int(runs.ts_capped.sum()),
        )
    # AISE/AISC against the table's MDM row of the same variant, else its default MDM row.
    mdm_of: dict[tuple[str, str, int, str], Case] = {}
    for row in rows:
        if row.case.method.startswith("MDM"):
            key = (row.table, row.case.scenario, row.case.n_uav, row.case.variant)
            mdm_of.setdefault(key, row.case)
    out = []
    for row in rows:
        case = row.case
        tnc, ts, capped = stats[case]
        aise = aisc = None
        mdm_case = mdm_of.get(
            (row.table, case.scenario, case.n_uav, case.variant),
            mdm_of.get((row.table, case.scenario, case.n_uav, "")),
        )
        if not case.method.startswith("MDM") and mdm_case is not None:
            mdm_tnc, mdm_ts, _ = stats[mdm_case]
            aise = _rounded(metrics.aise(mdm_tnc.mean, tnc.mean))
            if results[case].has_ts:
                aisc = _rounded(metrics.aisc(mdm_ts.mean, ts.mean))
        has_ts = results[case].has_ts
        levels = case.method.removeprefix("MDM:").split("+")
        paper = row.paper
        out.append(
            MeasuredRow(
                table=row.table,
                scenario=case.scenario,
                method="MDM" if case.method.startswith("MDM") else case.method,
                level1=levels[0],
                level2=levels[1] if len(levels) > 1 else "",
                delta1_pct_L=case.delta1_pct,
                n_uav=case.n_uav,
                n_targets=len(results[case].profile.targets),
                n_false=case.n_false,
                tnc_mean=round(tnc.mean, 3),
                tnc_std=round(tnc.std, 3),
                ts_mean_s=round(ts.mean) if has_ts else None,
                ts_std_s=round(ts.std) if has_ts else None,
                aise_pct=aise,
                aisc_pct=aisc,
                runs=tnc.n,
                capped=capped if has_ts else None,
                tnc_ci95=(round(tnc.ci_low, 3), round(tnc.ci_high, 3)),
                paper_tnc_mean=paper.tnc_mean if paper else None,
                paper_ts_mean_s=paper.ts_mean_s if paper else None,
                tnc_within=_within(
                    tnc.mean, paper.tnc_mean if paper else None, TNC_TOLERANCE[case.scenario]
                ),
                ts_within=_within(
                    ts.mean, paper.ts_mean_s if paper and has_ts else None, TS_TOLERANCE
                ),
                peer_follow_pct=_pct(results[case].follow_share),
                variant=VARIANTS[case.variant][0] if case.variant else "",
            )
        )
    return out


def format_table(rows: list[MeasuredRow]) -> str:
    """A Markdown table of measured rows beside the paper's numbers."""
    head = (
        "| table | scenario | method | L1 | L2 | δ1 %L | UAVs | false | T_nc (ours) | T_nc (paper) | in tol |"
        " T_S s (ours) | T_S s (paper) | in tol | AISE % | AISC % | runs | capped | follows peer % |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    )
    lines = [head]
    for r in rows:

        def mark(v: bool | None) -> str:
            return "" if v is None else ("yes" if v else "**no**")

        def num(v: float | None, fmt: str) -> str:
            return "" if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, fmt)

        ts = "" if r.ts_mean_s is None else f"{r.ts_mean_s:.0f} ± {r.ts_std_s:.0f}"
        lines.append(
            f"| {r.table} | {r.scenario} | {r.method}{f' ({r.variant})' if r.variant else ''} | {r.level1} | {r.level2} | {r.delta1_pct_L:g} | "
            f"{r.n_uav} | {r.n_false} | {r.tnc_mean:.3f} ± {r.tnc_std:.3f} | {num(r.paper_tnc_mean, '.3f')} | "
            f"{mark(r.tnc_within)} | {ts} | {num(r.paper_ts_mean_s, '.0f')} | "
            f"{mark(r.ts_within)} | {num(r.aise_pct, '.1f')} | {num(r.aisc_pct, '.1f')} | {r.runs} | {num(r.capped, 'd')} |"
            f" {num(r.peer_follow_pct, '.1f')} |"
        )
    return "\n".join(lines)
