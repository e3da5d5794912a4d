"""The `reproduce` report folder: report.md (a summary first, then every row beside the paper's,
section III-B and the claims about Figs. 4-9), results.csv and the figures."""

from __future__ import annotations

import csv
import gc
import os
from collections import Counter
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from mdm_montecarlo.engines.local_pool import imap_unordered
from mdm_montecarlo.engines.runner import MissionResults
from mdm_montecarlo.study.cases import (
    SECTION3B_METHODS,
    TNC_TOLERANCE,
    TS_TOLERANCE,
    Case,
    Row,
)
from mdm_montecarlo.study.figure_claims import Claim, check_claims
from mdm_montecarlo.study.known_causes import cause_of, slug
from mdm_montecarlo.study.plots import plot_scaling, plot_section3b, plot_table
from mdm_montecarlo.study.reading_report import reading_rows, readings_section
from mdm_montecarlo.study.readings import CLOSEST, DEFAULT, READINGS, reading_cases
from mdm_montecarlo.study.report_comparisons import comparison_section
from mdm_montecarlo.study.section3b import SearchGeometry, confirmed_share, p_cm, p_cs
from mdm_montecarlo.study.tables import MeasuredRow, format_table

Plot = tuple[Callable[..., None], tuple[Any, ...]]
_MODEL = Path(__file__).resolve().parents[2] / "docs" / "model.md"
SECTION3B_TIMES = (1000.0, 5000.0, 10000.0, 20000.0, 40000.0)


def write_csv(path: Path, rows: list[MeasuredRow]) -> None:
    """All measured rows with the paper's figures beside them."""
    with path.open("w", newline="", encoding="utf-8") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0].as_dict()))
        writer.writeheader()
        for r in rows:
            writer.writerow(r.as_dict())


def _model_link(folder: Path) -> str:
    """docs/model.md relative to the report folder (so the links work in a checkout)."""
    if _MODEL.exists():
        return Path(os.path.relpath(_MODEL, folder.resolve())).as_posix()
    return "docs/model.md"


def _outside(measured: list[MeasuredRow]) -> list[tuple[MeasuredRow, str, float, float]]:
    """(row, metric, ours, paper) for every mean outside the tolerance."""
    out = []
    for m in measured:
        if m.tnc_within is False and m.paper_tnc_mean is not None:
            out.append((m, "T_nc", m.tnc_mean, m.paper_tnc_mean))
        if m.ts_within is False and m.paper_ts_mean_s is not None and m.ts_mean_s is not None:
            out.append((m, "T_S", float(m.ts_mean_s), m.paper_ts_mean_s))
    return out


def _row_name(m: MeasuredRow) -> str:
    levels = f" {m.level1}+{m.level2}" if m.method == "MDM" else ""
    variant = f" ({m.variant})" if m.variant else ""
    delta = f", δ1 {m.delta1_pct_L:g} %" if m.table == "simtable3" else ""
    return f"{m.table} {m.scenario} {m.method}{levels}{variant}{delta}"


def summary(measured: list[MeasuredRow], docs: str, claims: list[Claim], reading: str) -> list[str]:
    """The report's first screen: how many of the reading's rows are inside, and why the
    others are not."""
    tnc = [m.tnc_within for m in measured if m.tnc_within is not None]
    ts = [m.ts_within for m in measured if m.ts_within is not None]
    lines = [
        "## Summary",
        "",
        f"Reading `{reading}` ([Readings](#readings)): {READINGS[reading].label()}.",
        "",
        f"- **T_nc inside tolerance: {sum(tnc)} of {len(tnc)} rows; T_S: {sum(ts)} of "
        f"{len(ts)} rows** (tolerances: mean T_nc within "
        + ", ".join(f"{int(v * 100)} % {k}" for k, v in TNC_TOLERANCE.items())
        + f"; mean T_S within {int(TS_TOLERANCE * 100)} %).",
    ]
    by_scenario: dict[str, list[bool]] = {}
    for m in measured:
        if m.tnc_within is not None:
            by_scenario.setdefault(m.scenario, []).append(m.tnc_within)
    lines.append(
        "- T_nc inside by scenario: "
        + ", ".join(f"{k} {sum(v)}/{len(v)}" for k, v in by_scenario.items())
        + "."
    )
    outside = _outside(measured)
    if outside:
        counts = Counter(cause_of(m, metric).heading for m, metric, _, _ in outside)
        lines.append("- Known causes of the means outside tolerance (rows per cause):")
        for heading, n in counts.most_common():
            lines.append(f"  - [{heading}]({docs}#{slug(heading)}): {n}")
    if claims:
        held = sum(c.holds for c in claims)
        lines.append(
            f"- Claims about Figs. 4-9: {held} of {len(claims)} hold "
            "([checked below](#claims-about-figs-4-9))."
        )
    lines += [
        "",
        "Details: [means outside tolerance](#means-outside-tolerance) (every row), "
        f"[outside under {CLOSEST}](#outside-under-{CLOSEST}), then every table.",
        "",
    ]
    return lines


def outside_table(
    measured: list[MeasuredRow], docs: str, heading: str = "Means outside tolerance"
) -> list[str]:
    """Every mean outside tolerance, with its docs/model.md entry and closest variant."""
    rows = _outside(measured)
    lines = [f"## {heading}", ""]
    if not rows:
        return [*lines, "None.", ""]
    lines += [
        "| row | metric | ours | paper | difference | why (docs/model.md) | closest variant |",
        "|---|---|---|---|---|---|---|",
    ]
    for m, metric, ours, paper in rows:
        cause = cause_of(m, metric)
        fmt = ".3f" if metric == "T_nc" else ".0f"
        lines.append(
            f"| {_row_name(m)} | {metric} | {ours:{fmt}} | {paper:{fmt}} | "
            f"{(ours - paper) / paper * 100:+.1f} % | [{cause.heading}]({docs}#{cause.anchor}) | "
            f"{cause.closest(m, metric)} |"
        )
    return [*lines, ""]


def section3b(folder: Path, results: dict[Case, MissionResults], plots: list[Plot]) -> list[str]:
    """P_CS and P_CM beside the simulated share of confirmed targets, with eq. (22)'s claim."""
    cases = [Case("fixed", m, 20.0, 1, 0) for m in SECTION3B_METHODS]
    if not all(c in results for c in cases):
        return []
    single, mdm = (results[c] for c in cases)
    profile = single.profile
    geometry = SearchGeometry(
        area=profile.area.north * profile.area.east,
        speed=profile.fleet.speed,
        confirm_radius=profile.sensors[-1].radius,
        detect_radius=profile.sensors[0].radius,
    )
    png = "section3b-pcs-pcm.png"
    plots.append((plot_section3b, (str(folder / png), geometry, single, mdm)))
    t = np.array(SECTION3B_TIMES)
    sim_s, sim_m = confirmed_share(single.team_times, t), confirmed_share(mdm.team_times, t)
    theory_s, theory_m = p_cs(t, geometry), p_cm(t, geometry)
    lines = [
        "## Section III-B: P_CS and P_CM against simulation",
        "",
        "One UAV searches paper-fixed's ten targets (single-sensor US, and MDM LS+BS); the "
        "simulated value is the share of (run, target) pairs confirmed by t. P_CM averages "
        "eq. (19) over a detection time t_d drawn from eq. (18)'s law with r_1 (the paper "
        "leaves t_d open; mdm_montecarlo/study/section3b.py).",
        "",
        "| t (s) | P_CS eq. (18) | simulated US | P_CM eqs. (19)-(20) | simulated MDM |"
        " eq. (22) P_CM >= P_CS, simulated |",
        "|---|---|---|---|---|---|",
    ]
    for i, ti in enumerate(t):
        holds = "yes" if sim_m[i] >= sim_s[i] else "**no**"
        lines.append(
            f"| {ti:.0f} | {theory_s[i]:.3f} | {sim_s[i]:.3f} | {theory_m[i]:.3f} | "
            f"{sim_m[i]:.3f} | {holds} |"
        )
    lines += ["", f"![P_CS and P_CM]({png})", ""]
    return lines


def claims_section(claims: list[Claim]) -> list[str]:
    if not claims:
        return []
    lines = [
        "## Claims about Figs. 4-9",
        "",
        "Measured on the 'scaling' rows (box plots below).",
        "",
        "| figure | claim (paper) | measured | holds |",
        "|---|---|---|---|",
    ]
    for c in claims:
        lines.append(f"| {c.figure} | {c.text} | {c.measured} | {'yes' if c.holds else '**no**'} |")
    return [*lines, ""]


def write_report(
    folder: Path,
    rows: list[Row],
    measured: list[MeasuredRow],
    results: dict[Case, MissionResults],
    header: str,
    workers: int = 1,
    meanwhile: Callable[[], object] | None = None,
    reading: str = DEFAULT,
) -> Path:
    """Write report.md, results.csv and PNGs into ``folder``; returns the report path.

    ``workers`` > 1 draws the plots in that many processes. ``meanwhile`` (the other result
    files) runs in a thread while the plots are drawn; report.md is written once both are
    done, and an exception of ``meanwhile`` is raised here.
    """
    folder.mkdir(parents=True, exist_ok=True)
    plots: list[Plot] = []
    write_csv(folder / "results.csv", measured)
    docs = _model_link(folder)
    tables = list(dict.fromkeys(r.table for r in rows))
    scaling = "scaling" in tables
    claims = check_claims(reading_cases(results, reading)) if scaling else []
    lines = [
        "# Section IV reproduced",
        "",
        header,
        "",
        *summary(reading_rows(measured, reading), docs, claims, reading),
        *readings_section(measured, results, docs, with_figures=scaling),
        *outside_table(measured, docs),
        *outside_table(reading_rows(measured, CLOSEST), docs, f"Outside under {CLOSEST}"),
        *comparison_section(rows, results),
        "Single-sensor and swarm AISE/AISC are against the MDM row of the same table, scenario "
        "and variant (the default MDM row where the variant has none) "
        "(blank where the single-sensor row's mean is 0: a percentage of it is undefined); "
        "'follows peer %' is the share of a swarm's particle-iterations that followed a best "
        "heard from another vehicle.",
        "",
    ]
    for table in tables:
        if table == "section3b":
            lines += section3b(folder, results, plots)
            continue
        mine = [m for m in measured if m.table == table]
        lines += [f"## {table}", "", format_table(mine), ""]
        inside = [m.tnc_within for m in mine if m.tnc_within is not None]
        if inside:
            lines.append(f"T_nc inside tolerance: {sum(inside)} of {len(inside)} rows.")
            ts_in = [m.ts_within for m in mine if m.ts_within is not None]
            if ts_in:
                lines.append(f"T_S inside tolerance: {sum(ts_in)} of {len(ts_in)} rows.")
            lines.append("")
        if table == "scaling":
            lines += claims_section(claims)
        for scenario in dict.fromkeys(r.case.scenario for r in rows if r.table == table):
            png = f"{table}-{scenario}.png"
            mine_rows = [r for r in rows if r.table == table and r.case.scenario == scenario]
            cases = list(dict.fromkeys(r.case for r in mine_rows))
            of_plot = {c: results[c] for c in cases}
            if table == "scaling":
                methods = list(dict.fromkeys(c.method for c in cases))
                plots.append((plot_scaling, (str(folder / png), scenario, methods, of_plot)))
            else:
                paper = {
                    r.case: (r.paper.tnc_mean, r.paper.ts_mean_s) for r in mine_rows if r.paper
                }
                plots.append(
                    (plot_table, (str(folder / png), table, scenario, cases, of_plot, paper))
                )
            lines += [f"![{table} {scenario}]({png})", ""]
    _draw(plots, workers, meanwhile)
    path = folder / "report.md"
    path.write_text("\n".join(lines), encoding="utf-8")
    return path


def _draw(plots: list[Plot], workers: int, meanwhile: Callable[[], object] | None) -> None:
    """Draw the plots, in ``workers`` processes if more than one, with ``meanwhile`` in a
    thread of this process, started once the plot workers are forked (a fork while another
    thread runs could copy a lock it holds). Waits for both, also when the drawing fails or
    is interrupted: no result file is left half written."""
    side: list[Future[object]] = []
    with ThreadPoolExecutor(max_workers=1) as pool:

        def start() -> None:
            if meanwhile is not None:
                side.append(pool.submit(meanwhile))

        if workers <= 1 or len(plots) <= 1:
            start()
            for plot, args in plots:
                plot(*args)
        else:
            for _ in imap_unordered(_plot, list(plots), workers, started=start):
                pass
    for done in side:
        done.result()


def _plot(plot: Callable[..., None], args: tuple[Any, ...]) -> None:
    # A plot worker draws a few figures and exits. Each figure leaves ~10 000 objects of cyclic
    # garbage; collecting them was a tenth of the report's CPU, and the exit returns the memory anyway.
    gc.disable()
    plot(*args)
