"""The report's tests of the paper's main claims: in each scenario of the tables named in
COMPARED_TABLES, MDM against the best single-sensor search (highest mean T_nc of US, BS, LS)
and against each swarm baseline, with compare.py's statistics (difference MDM - other)."""

from __future__ import annotations

from mdm_montecarlo.engines.runner import MissionResults
from mdm_montecarlo.study.cases import Case, Row
from mdm_montecarlo.study.compare import Comparison, compare_samples
from mdm_montecarlo.study.samples import run_outcomes
from mdm_montecarlo.study.variants import METHODS, SWARM_METHODS

COMPARED_TABLES = ("simtable1", "simtablepso1")
REPORT_RESAMPLES = 2000
"""Bootstrap resamples in the report (`compare` defaults to 10000), a quarter of the CPU or
less: measured on paper-fixed US against MDM (1000 runs each, seed 2024), the interval's
ends moved by 2-3 % of its width between 2000 and 10000 resamples."""


def _pairs(rows: list[Row], results: dict[Case, MissionResults]) -> list[tuple[str, Case, Case]]:
    """(table, other, MDM) for every comparison the section makes, in the report's order."""
    pairs = []
    for table in COMPARED_TABLES:
        mine = [r.case for r in rows if r.table == table and r.case in results]
        for scenario in dict.fromkeys(c.scenario for c in mine):
            cases = [c for c in mine if c.scenario == scenario and not c.variant]
            mdm = next((c for c in cases if c.method.startswith("MDM")), None)
            if mdm is None:
                continue
            single = [c for c in cases if c.method in METHODS]
            if single:
                best = max(single, key=lambda c: float(results[c].tnc.mean()))
                pairs.append((table, best, mdm))
            pairs += [(table, c, mdm) for c in cases if c.method in SWARM_METHODS]
    return pairs


def _comparisons(a: MissionResults, b: MissionResults) -> list[Comparison]:
    x, y = run_outcomes(a), run_outcomes(b)
    out = [compare_samples("T_nc", x.tnc, y.tnc, resamples=REPORT_RESAMPLES)]
    if x.ts is not None and y.ts is not None:
        out.append(compare_samples("T_S", x.ts, y.ts, resamples=REPORT_RESAMPLES))
    return out


def comparison_section(rows: list[Row], results: dict[Case, MissionResults]) -> list[str]:
    """The report's section; empty where no compared table was run."""
    pairs = _pairs(rows, results)
    if not pairs:
        return []
    lines = [
        "## MDM against the best single sensor and against the swarms",
        "",
        "Difference = mean MDM - mean of the other method, with Welch's 95 % interval, the "
        f"two-sided Mann-Whitney U test, a {REPORT_RESAMPLES}-resample bootstrap interval and "
        "Cohen's d (`mdm-montecarlo compare` gives the same for any two result folders or "
        "configurations). Both rows of a pair use the same seed, so they share targets and "
        "start points; the tests are those for independent samples, which overstate the "
        "spread of the difference when the pair's outcomes are positively correlated "
        "(their p values are then too large, not too small). "
        "'best single sensor': the highest mean T_nc of US, BS and LS in that scenario.",
        "",
        "| table | scenario | MDM | against | metric | mean MDM | mean other | difference |"
        " 95 % CI | p (U) | bootstrap 95 % CI | Cohen's d |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for table, other, mdm in pairs:
        for c in _comparisons(results[other], results[mdm]):
            f = ".3f" if c.metric == "T_nc" else ".0f"
            lines.append(
                f"| {table} | {mdm.scenario} | {mdm.method.removeprefix('MDM:')} | "
                f"{other.method} | {c.metric} | {c.mean_b:{f}} | {c.mean_a:{f}} | "
                f"{c.difference:+{f}} | [{c.ci95[0]:{f}}, {c.ci95[1]:{f}}] | "
                f"{c.mann_whitney_p:.2g} | [{c.bootstrap_ci95[0]:{f}}, {c.bootstrap_ci95[1]:{f}}]"
                f" | {c.cohens_d:+.2f} |"
            )
    return [*lines, ""]
