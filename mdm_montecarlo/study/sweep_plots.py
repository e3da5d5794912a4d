"""A sweep's figures: one per metric, its mean against the first varied field with the 95 %
confidence band, one line per combination of the other varied fields."""

from __future__ import annotations

import itertools

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from mdm_montecarlo.study.sweep import SweepAsk
from mdm_montecarlo.study.sweep_table import PointRow

DPI = 110
METRICS = {
    "tnc": ("T_nc", "targets confirmed T_nc (mean, 95 % CI)"),
    "ts": ("T_S", "time to confirm all targets T_S, s (mean, 95 % CI)"),
}


def _numeric(values: list[str]) -> list[float] | None:
    try:
        return [float(v) for v in values]
    except ValueError:
        return None


def plot_metric(path: str, ask: SweepAsk, rows: list[PointRow], metric: str, title: str) -> None:
    """``metric`` 'tnc' or 'ts': the mean of every point and its 95 % interval as a band."""
    (x_key, x_values), others = ask.vary[0], ask.vary[1:]
    numeric = _numeric(x_values)
    where = np.array(numeric) if numeric is not None else np.arange(len(x_values), dtype=float)
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    combos = list(itertools.product(*(v for _, v in others))) or [()]
    for combo in combos:
        mine = [
            r
            for r in rows
            if all(r.values[k] == v for (k, _), v in zip(others, combo, strict=True))
        ]
        stats = [r.tnc if metric == "tnc" else r.ts for r in mine]
        if not stats or any(s is None for s in stats):
            continue
        x = where[[x_values.index(r.values[x_key]) for r in mine]]
        by_x = np.argsort(x, kind="stable")  # values given in any order: a line left to right
        x = x[by_x]
        mean = np.array([s.mean for s in stats if s is not None])[by_x]
        low = np.array([s.ci_low for s in stats if s is not None])[by_x]
        high = np.array([s.ci_high for s in stats if s is not None])[by_x]
        label = ", ".join(f"{k}={v}" for (k, _), v in zip(others, combo, strict=True)) or "mean"
        (line,) = ax.plot(x, mean, marker="o", label=label)
        ax.fill_between(x, low, high, color=line.get_color(), alpha=0.2, linewidth=0)
    if numeric is None:
        ax.set_xticks(where, x_values)
    ax.set_xlabel(x_key)
    ax.set_ylabel(METRICS[metric][1])
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best", title="band: 95 % CI of the mean", title_fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
