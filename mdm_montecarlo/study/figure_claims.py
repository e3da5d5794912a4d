"""The paper's textual claims about Figs. 4-9 (6, 12 and 24 UAVs), checked on the 'scaling'
rows: each claim as printed, the figures it is about as measured, and whether it holds."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mdm_montecarlo.engines.runner import MissionResults
from mdm_montecarlo.study.cases import SCALING_FLEETS, Case

FloatArray = NDArray[np.float64]
SINGLE = ("US", "BS", "LS")
MDM_OF = {"fixed": "MDM:LS+BS", "popup": "MDM:US+US", "dynamic": "MDM:LS+BS"}
SAME_MEAN = 0.05
"""Fig. 8's "remains the same for all the 4 methods": means within 5 % of each other."""


@dataclass(frozen=True)
class Claim:
    figure: str
    text: str
    """The claim as the paper words it (shortened)."""
    measured: str
    holds: bool


Results = dict[Case, MissionResults]


def _values(results: Results, scenario: str, method: str, n: int, metric: str) -> FloatArray:
    res = results[Case(scenario, method, 20.0, n, 0)]
    return np.asarray(res.tnc if metric == "tnc" else res.ts()[0], dtype=float)


def _per_fleet(
    results: Results,
    scenario: str,
    metric: str,
    stat: Callable[[FloatArray], float],
    fleets: tuple[int, ...] = SCALING_FLEETS,
) -> list[tuple[int, float, dict[str, float]]]:
    """(fleet, MDM's statistic, the single-sensor methods' statistics) per fleet size."""
    out = []
    for n in fleets:
        mdm = stat(_values(results, scenario, MDM_OF[scenario], n, metric))
        others = {m: stat(_values(results, scenario, m, n, metric)) for m in SINGLE}
        out.append((n, mdm, others))
    return out


def _fmt(rows: list[tuple[int, float, dict[str, float]]], digits: int) -> str:
    parts = []
    for n, mdm, others in rows:
        rest = "/".join(f"{v:.{digits}f}" for v in others.values())
        parts.append(f"{n} UAVs: MDM {mdm:.{digits}f}, US/BS/LS {rest}")
    return "; ".join(parts)


def _best(rows: list[tuple[int, float, dict[str, float]]], higher: bool) -> bool:
    if higher:
        return all(mdm > max(o.values()) for _, mdm, o in rows)
    return all(mdm < min(o.values()) for _, mdm, o in rows)


def _max(v: FloatArray) -> float:
    return float(v.max())


def _min(v: FloatArray) -> float:
    return float(v.min())


def _mean(v: FloatArray) -> float:
    return float(v.mean())


def _iqr(v: FloatArray) -> float:
    q1, q3 = np.percentile(v, [25, 75])
    return float(q3 - q1)


def check_claims(results: Results) -> list[Claim]:
    """Every claim about Figs. 4-9; needs the 'scaling' cases in ``results``."""
    claims: list[Claim] = []
    for stat, word, digits in ((_max, "maximum", 0), (_min, "minimum", 0), (_mean, "mean", 3)):
        rows = _per_fleet(results, "fixed", "tnc", stat)
        claims.append(
            Claim(
                "Fig. 4 (fixed, efficiency)",
                f"MDM (LS+BS) has the highest {word} T_nc for 6, 12 and 24 UAVs",
                _fmt(rows, digits),
                _best(rows, higher=True),
            )
        )
    rows = _per_fleet(results, "fixed", "ts", _max)
    claims.append(
        Claim(
            "Fig. 5 (fixed, completeness)",
            "MDM's worst-case T_S is 50 % less than the other techniques' worst case",
            _fmt(rows, 0) + " (runs that never finish count as the 40 000 s cap)",
            all(mdm <= 0.5 * min(o.values()) for _, mdm, o in rows),
        )
    )
    rows = _per_fleet(results, "popup", "tnc", _max, (6, 12))
    printed = {6: (7, 6), 12: (9, 8)}
    claims.append(
        Claim(
            "Fig. 6 (pop-up, efficiency)",
            "MDM (US+US) confirms at most 7 and 9 targets with 6 and 12 UAVs, the others 6 and 8",
            _fmt(rows, 0),
            all((mdm, max(o.values())) == printed[n] for n, mdm, o in rows),
        )
    )
    rows = _per_fleet(results, "popup", "tnc", _mean)
    claims.append(
        Claim(
            "Fig. 6 (pop-up, efficiency)",
            "MDM (US+US) has the highest mean T_nc for 6, 12 and 24 UAVs",
            _fmt(rows, 3),
            _best(rows, higher=True),
        )
    )
    for stat, word in ((_min, "best-case"), (_max, "worst-case")):
        rows = _per_fleet(results, "popup", "ts", stat)
        claims.append(
            Claim(
                "Fig. 7 (pop-up, completeness)",
                f"MDM (US+US) has the lowest {word} T_S for 6, 12 and 24 UAVs",
                _fmt(rows, 0),
                _best(rows, higher=False),
            )
        )
    rows = _per_fleet(results, "popup", "ts", _iqr)
    claims.append(
        Claim(
            "Fig. 7 (pop-up, completeness)",
            "the quartile range of T_S is smaller for MDM (US+US) than for US, BS and LS",
            "interquartile range, s: " + _fmt(rows, 0),
            _best(rows, higher=False),
        )
    )
    rows = _per_fleet(results, "dynamic", "tnc", _mean)
    at24 = [r for r in rows if r[0] == 24]
    same = [r for r in rows if r[0] != 24]
    claims.append(
        Claim(
            "Fig. 8 (dynamic, efficiency)",
            "MDM (LS+BS) is better with 24 UAVs; with 6 and 12 all four methods are the same "
            f"(read as: means within {SAME_MEAN:.0%})",
            _fmt(rows, 3),
            _best(at24, higher=True)
            and all(
                max(mdm, *o.values()) <= (1 + SAME_MEAN) * min(mdm, *o.values())
                for _, mdm, o in same
            ),
        )
    )
    rows = _per_fleet(results, "dynamic", "ts", _min)
    claims.append(
        Claim(
            "Fig. 9 (dynamic, completeness)",
            "MDM (LS+BS) has the lowest best-case T_S for 6, 12 and 24 UAVs",
            _fmt(rows, 0),
            _best(rows, higher=False),
        )
    )
    return claims
