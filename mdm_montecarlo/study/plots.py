"""The report's figures: box plots like the paper's Figs. 4-9 and tables, and the section III-B
curves. Every figure has axis titles and the varied parameter on its x-axis, and is sized so
its labels do not overlap at page width."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from mdm_montecarlo.engines.runner import MissionResults
from mdm_montecarlo.study.cases import SCALING_FLEETS, Case
from mdm_montecarlo.study.section3b import SearchGeometry, confirmed_share, p_cm, p_cs

DPI = 110
_COLOURS = ("#4c72b0", "#dd8452", "#55a868", "#c44e52")


def _save(fig: Figure, path: str) -> None:
    """Lay the figure out once, then draw and write it once. After ``tight_layout`` a figure
    keeps a placeholder layout engine, and with any engine set ``savefig`` lays out the whole
    figure again (every text measured) before drawing it: a third of the report's CPU. The
    layout is measured at the PNG's dpi, so the drawing reuses its text measures; zlib level 3
    encodes the PNG in about 60 % of the default level 6's time, 0.5 % larger."""
    fig.set_dpi(DPI)
    fig.tight_layout()
    fig.set_layout_engine(None)
    fig.savefig(path, dpi=DPI, pil_kwargs={"compress_level": 3})
    plt.close(fig)


def _inside_legend(ax: Axes) -> None:
    """The legend at its 'best' place, left out of the layout: a 'best' legend lies inside the
    axes, so the tight layout is the same without it, and its place (tested against every line
    of the boxes) is found once, when the figure is drawn, not again in each layout pass."""
    ax.legend(fontsize=8, loc="best").set_in_layout(False)


def _axis_of(table: str) -> tuple[str, str]:
    """What varies along the x-axis of a table's plot: (axis title, label kind)."""
    if table == "simtable3":
        return "level-1 step length δ1 (% of L)", "delta1"
    if table in ("simtable4", "simtable5", "Dsimtable6"):
        return "distributions of level 1 + level 2 (MDM)", "levels"
    return "search method", "method"


_VARIANT_TICKS = {
    "eq10": "eq. 10",
    "popup_from_0": "t_i=200(i-1)",
    "targets_leave": "leave",
    "renew": "renewed",
    "popup_from_0_renew": "t_i=200(i-1), renewed",
    "targets_leave_renew": "leave, renewed",
    "swarm_forgets": "forgets",
    "swarm_waypoint_detection": "r_1 waypoints",
    "swarm_detection": "r_1 every 5 s",
    "lawnmower": "not in paper",
}
"""Short x tick names of the variants of study.VARIANTS (the report's tables give the labels)."""
PaperMeans = dict[Case, tuple[float | None, float | None]]
"""The paper's mean T_nc and T_S of a plotted case (None where it prints none)."""


def case_label(case: Case, kind: str) -> str:
    """The x tick label of a case: its δ1, its two distributions, or its method."""
    if kind == "delta1":
        return f"{case.delta1_pct:g}"
    if kind == "levels":
        return case.method.removeprefix("MDM:")
    label = case.method.replace("MDM:", "MDM ")
    return f"{label}\n({_VARIANT_TICKS[case.variant]})" if case.variant else label


def _boxes(
    ax: Axes,
    data: list[list[float]],
    labels: list[str],
    xlabel: str,
    ylabel: str,
    paper: list[float | None],
) -> None:
    """Box plots with our mean (a triangle) and the paper's mean (a red diamond, where it
    prints one) on each box."""
    ax.boxplot(
        data,
        tick_labels=labels,
        showmeans=True,
        meanprops={"marker": "^", "markerfacecolor": _COLOURS[2], "markeredgecolor": "black"},
    )
    where = [k + 1 for k, v in enumerate(paper) if v is not None]
    ax.plot([], [], "^", color=_COLOURS[2], markeredgecolor="black", label="our mean")
    if where:
        ax.plot(
            where,
            [v for v in paper if v is not None],
            "D",
            color=_COLOURS[3],
            markeredgecolor="black",
            label="paper's mean",
        )
    _inside_legend(ax)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(axis="y", alpha=0.3)
    if max((len(s) for s in labels), default=0) * len(labels) > 48:
        ax.tick_params(axis="x", labelrotation=30)


def plot_table(
    path: str,
    table: str,
    scenario: str,
    cases: list[Case],
    results: dict[Case, MissionResults],
    paper: PaperMeans,
) -> None:
    """Box plots of T_nc and, where the rows have one, T_S for the rows of one table and
    scenario, each with our mean and the paper's beside it. Rows simulated only to the
    mission duration (the swarms) have no T_S box."""
    xlabel, kind = _axis_of(table)
    labels = [case_label(c, kind) for c in cases]
    timed = [i for i, c in enumerate(cases) if results[c].has_ts]
    panels = 2 if timed else 1
    width = max(5.5, 0.75 * len(cases) + 1.5)
    # Many boxes: panels one above the other, so the figure stays about a page wide.
    stacked = panels == 2 and len(cases) > 5
    grid = (2, 1) if stacked else (1, panels)
    size = (width, 7.6) if stacked else (width * panels, 4.0)
    fig, axes = plt.subplots(*grid, figsize=size, squeeze=False)
    axes = axes.reshape(-1)[None, :]
    a = axes[0, 0]
    _boxes(
        a,
        [list(results[c].tnc) for c in cases],
        labels,
        xlabel,
        "targets confirmed T_nc",
        [paper.get(c, (None, None))[0] for c in cases],
    )
    a.set_title(f"{table}, {scenario} targets: efficiency", fontsize=10)
    if timed:
        b = axes[0, 1]
        _boxes(
            b,
            [list(results[cases[i]].ts()[0]) for i in timed],
            [labels[i] for i in timed],
            xlabel,
            "time to confirm all targets T_S (s)",
            [paper.get(cases[i], (None, None))[1] for i in timed],
        )
        b.set_title(f"{table}, {scenario} targets: completeness", fontsize=10)
        if len(timed) < len(cases):
            b.text(
                0.02,
                0.97,
                "swarm rows: simulated to the mission\nduration only, no T_S (as in the paper)",
                transform=b.transAxes,
                fontsize=8,
                va="top",
            )
    _save(fig, path)


def plot_scaling(
    path: str, scenario: str, methods: list[str], results: dict[Case, MissionResults]
) -> None:
    """Figs. 4-9: T_nc and T_S boxes per method, grouped by fleet size on the x-axis."""
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.2))
    width = 0.8 / len(methods)
    for ax, metric in zip(axes, ("tnc", "ts"), strict=True):
        for k, method in enumerate(methods):
            data = []
            for n in SCALING_FLEETS:
                res = results[Case(scenario, method, 20.0, n, 0)]
                data.append(list(res.tnc) if metric == "tnc" else list(res.ts()[0]))
            where = np.arange(len(SCALING_FLEETS)) + (k - (len(methods) - 1) / 2) * width
            box = ax.boxplot(data, positions=where, widths=width * 0.85, patch_artist=True)
            for patch in box["boxes"]:
                patch.set_facecolor(_COLOURS[k % len(_COLOURS)])
                patch.set_alpha(0.6)
            box["boxes"][0].set_label(method.replace("MDM:", "MDM "))
        ax.set_xticks(np.arange(len(SCALING_FLEETS)), [str(n) for n in SCALING_FLEETS])
        ax.set_xlabel("number of UAVs")
        kind = "efficiency" if metric == "tnc" else "completeness"
        ax.set_ylabel("targets confirmed T_nc" if metric == "tnc" else "T_S (s)")
        ax.set_title(f"{scenario} targets: {kind} vs number of UAVs", fontsize=10)
        ax.grid(axis="y", alpha=0.3)
        _inside_legend(ax)
    _save(fig, path)


def plot_section3b(
    path: str, geometry: SearchGeometry, single: MissionResults, mdm: MissionResults
) -> None:
    """P_CS (eq. 18) and P_CM (eqs. 19-20 averaged over t_d) against the simulated share of
    targets one UAV has confirmed by t, single-sensor US and MDM LS+BS."""
    horizon = single.profile.mission.ts_cap
    t = np.linspace(0.0, horizon, 201)
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    ax.plot(t, p_cs(t, geometry), color=_COLOURS[0], label="P_CS(t), eq. (18)")
    ax.plot(
        t,
        confirmed_share(single.team_times, t),
        color=_COLOURS[0],
        ls="--",
        label="simulated, single sensor (US)",
    )
    ax.plot(t, p_cm(t, geometry), color=_COLOURS[3], label="P_CM(t), eqs. (19)-(20), t_d ~ P_D")
    ax.plot(
        t,
        confirmed_share(mdm.team_times, t),
        color=_COLOURS[3],
        ls="--",
        label="simulated, MDM (LS+BS)",
    )
    ax.set_xlabel("mission time t (s)")
    ax.set_ylabel("P(one UAV has confirmed a given target by t)")
    ax.set_title(
        f"Section III-B: one UAV, {single.runs} runs x {len(single.profile.targets)} fixed targets",
        fontsize=10,
    )
    ax.set_ylim(0, 1.02)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    _save(fig, path)
