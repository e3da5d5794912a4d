"""The `reproduce` report folder: report.md, results.csv and box plots like the paper's figures."""

from __future__ import annotations

import csv
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.axes import Axes

from mdm_montecarlo.runner import MissionResults
from mdm_montecarlo.study import SCALING_FLEETS, TNC_TOLERANCE, TS_TOLERANCE, Case, Row
from mdm_montecarlo.tables import MeasuredRow, format_table


def write_csv(path: Path, rows: list[MeasuredRow]) -> None:
    """All measured rows with the paper's figures beside them."""
    with path.open("w", newline="", encoding="utf-8") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0].as_dict()))
        writer.writeheader()
        for r in rows:
            writer.writerow(r.as_dict())


def _boxes(ax: Axes, data: list[list[float]], labels: list[str], ylabel: str, title: str) -> None:
    ax.boxplot(data, tick_labels=labels)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.grid(axis="y", alpha=0.3)


def plot_table(
    path: Path, title: str, cases: list[Case], results: dict[Case, MissionResults]
) -> None:
    """Box plots of T_nc and T_S for the methods of one table and scenario."""
    fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.6))
    labels = [c.method.replace("MDM:", "MDM ") for c in cases]
    _boxes(
        a,
        [list(results[c].tnc) for c in cases],
        labels,
        "targets confirmed T_nc",
        f"{title}: efficiency",
    )
    timed = [(c, label) for c, label in zip(cases, labels, strict=True) if results[c].has_ts]
    _boxes(
        b,
        [list(results[c].ts()[0]) for c, _ in timed],
        [label for _, label in timed],
        "time to confirm all T_S (s)",
        f"{title}: completeness",
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_scaling(
    path: Path, scenario: str, rows: list[Row], results: dict[Case, MissionResults]
) -> None:
    """The 6/12/24-UAV figures: boxes per method, grouped by fleet size."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8))
    for ax, metric in zip(axes, ("tnc", "ts"), strict=True):
        data, labels = [], []
        for n in SCALING_FLEETS:
            for row in rows:
                c = row.case
                if row.table == "scaling" and c.scenario == scenario and c.n_uav == n:
                    res = results[c]
                    data.append(list(res.tnc) if metric == "tnc" else list(res.ts()[0]))
                    labels.append(f"{c.method.replace('MDM:', 'MDM ')}\n{n}")
        name = "T_nc" if metric == "tnc" else "T_S (s)"
        kind = "efficiency" if metric == "tnc" else "completeness"
        _boxes(ax, data, labels, name, f"{scenario} targets: {kind} vs number of UAVs")
        ax.tick_params(axis="x", labelsize=6)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_report(
    folder: Path,
    rows: list[Row],
    measured: list[MeasuredRow],
    results: dict[Case, MissionResults],
    header: str,
    workers: int = 1,
) -> Path:
    """Write report.md, results.csv and PNGs into ``folder``; returns the report path.

    ``workers`` > 1 draws the plots in that many processes.
    """
    folder.mkdir(parents=True, exist_ok=True)
    plots: list[tuple[Callable[..., None], tuple[Any, ...]]] = []
    write_csv(folder / "results.csv", measured)
    lines = [
        "# Section IV reproduced",
        "",
        header,
        "",
        f"Tolerances: mean T_nc within {', '.join(f'{int(v * 100)} % ({k})' for k, v in TNC_TOLERANCE.items())}; "
        f"mean T_S within {int(TS_TOLERANCE * 100)} %. Single-sensor AISE/AISC are against the MDM row "
        "of the same table and scenario.",
        "",
    ]
    tables = list(dict.fromkeys(r.table for r in rows))
    for table in tables:
        mine = [m for m in measured if m.table == table]
        lines += [f"## {table}", "", format_table(mine), ""]
        inside = [m.tnc_within for m in mine if m.tnc_within is not None]
        if inside:
            lines.append(f"T_nc inside tolerance: {sum(inside)} of {len(inside)} rows.")
            ts_in = [m.ts_within for m in mine if m.ts_within is not None]
            if ts_in:
                lines.append(f"T_S inside tolerance: {sum(ts_in)} of {len(ts_in)} rows.")
            lines.append("")
        for scenario in dict.fromkeys(r.case.scenario for r in rows if r.table == table):
            png = f"{table}-{scenario}.png"
            if table == "scaling":
                plots.append((plot_scaling, (folder / png, scenario, rows, results)))
            else:
                cases = list(
                    dict.fromkeys(
                        r.case for r in rows if r.table == table and r.case.scenario == scenario
                    )
                )
                of_plot = {c: results[c] for c in cases}
                plots.append((plot_table, (folder / png, f"{table} {scenario}", cases, of_plot)))
            lines += [f"![{table} {scenario}]({png})", ""]
    _draw(plots, workers)
    path = folder / "report.md"
    path.write_text("\n".join(lines), encoding="utf-8")
    return path


def _draw(plots: list[tuple[Callable[..., None], tuple[Any, ...]]], workers: int) -> None:
    if workers <= 1 or len(plots) <= 1:
        for plot, args in plots:
            plot(*args)
        return
    with ProcessPoolExecutor(max_workers=workers) as pool:
        for done in [pool.submit(plot, *args) for plot, args in plots]:
            done.result()
