"""The report's "Readings" section: under each named reading (readings.READINGS), the rows
inside tolerance by scenario, and which of the paper's claims hold (MDM ahead of each
single-sensor search and each swarm, T_nc and T_S, every scenario; the claims about Figs. 4-9)."""

from __future__ import annotations

from dataclasses import dataclass

from mdm_montecarlo.engines.runner import MissionResults
from mdm_montecarlo.study.cases import VARIANTS, Case
from mdm_montecarlo.study.figure_claims import Claim, check_claims
from mdm_montecarlo.study.readings import READINGS, SCENARIOS, reading_cases, reading_named
from mdm_montecarlo.study.tables import MeasuredRow

AHEAD_TABLES = {"simtable1": ("US", "BS", "LS"), "simtablef1": ("US", "BS", "LS")}
"""Tables whose MDM row the paper sets ahead of each single-sensor row, T_nc and T_S."""
SWARM_TABLE = ("simtablepso1", ("PSO", "SPSO", "ARPSO"))
"""The swarm table: MDM ahead in T_nc (the paper prints no swarm T_S)."""


@dataclass(frozen=True)
class Ahead:
    """One "MDM ahead of X" claim as measured under a reading."""

    table: str
    scenario: str
    other: str
    metric: str
    mdm: float
    theirs: float

    @property
    def holds(self) -> bool:
        return self.mdm > self.theirs if self.metric == "T_nc" else self.mdm < self.theirs

    @property
    def claim(self) -> str:
        return f"{self.table} {self.scenario}: MDM ahead of {self.other} in {self.metric}"


def _base_key(m: MeasuredRow) -> tuple[object, ...]:
    return (m.table, m.scenario, m.method, m.level1, m.level2, m.delta1_pct_L, m.n_uav, m.n_false)


def reading_rows(measured: list[MeasuredRow], name: str) -> list[MeasuredRow]:
    """The rows a reading flies: each default row, or its variant row of the reading's first
    choice for its scenario that the report has (Reading.choices)."""
    choices = {k: [VARIANTS[v][0] for v in keys] for k, keys in reading_named(name).choices.items()}
    by_key = {(_base_key(m), m.variant): m for m in measured}
    out = []
    for m in measured:
        if m.variant:
            continue
        flown = [
            by_key[k] for w in choices.get(m.scenario, []) if (k := (_base_key(m), w)) in by_key
        ]
        out.append(flown[0] if flown else m)
    return out


def ahead_claims(rows: list[MeasuredRow]) -> list[Ahead]:
    """MDM against each single-sensor row (simtable1, simtablef1: T_nc and T_S) and each swarm
    row (simtablepso1: T_nc), per scenario, on one reading's rows."""
    tables = {**AHEAD_TABLES, SWARM_TABLE[0]: SWARM_TABLE[1]}
    out = []
    for table, others in tables.items():
        for scenario in SCENARIOS:
            mine = {m.method: m for m in rows if m.table == table and m.scenario == scenario}
            mdm = mine.get("MDM")
            if mdm is None:
                continue
            for other in others:
                theirs = mine.get(other)
                if theirs is None:
                    continue
                out.append(Ahead(table, scenario, other, "T_nc", mdm.tnc_mean, theirs.tnc_mean))
                if mdm.ts_mean_s is not None and theirs.ts_mean_s is not None:
                    out.append(
                        Ahead(table, scenario, other, "T_S", mdm.ts_mean_s, theirs.ts_mean_s)
                    )
    return out


def _counts(rows: list[MeasuredRow], attr: str) -> tuple[str, str]:
    """'inside/all' and the same by scenario, of the rows' ``attr`` verdicts."""
    by: dict[str, list[bool]] = {}
    for m in rows:
        verdict = getattr(m, attr)
        if verdict is not None:
            by.setdefault(m.scenario, []).append(verdict)
    every = [v for vs in by.values() for v in vs]
    per = ", ".join(f"{s} {sum(v)}/{len(v)}" for s, v in by.items())
    return f"{sum(every)}/{len(every)}", per


def readings_section(
    measured: list[MeasuredRow],
    results: dict[Case, MissionResults],
    docs: str,
    with_figures: bool,
) -> list[str]:
    """Rows inside tolerance under each reading, by scenario, and the claims that hold."""
    lines = [
        "## Readings",
        "",
        "Each reading flies every default row, or its row of the reading's choice for its "
        f"scenario ([One reading of the paper]({docs}#one-reading-of-the-paper); "
        "`--reading help` lists them).",
        "",
        "| reading | choices | T_nc inside | T_S inside | T_nc by scenario | T_S by scenario |"
        " MDM ahead (claims held) | Figs. 4-9 claims held |",
        "|---|---|---|---|---|---|---|---|",
    ]
    ahead: dict[str, list[Ahead]] = {}
    figures: dict[str, list[Claim]] = {}
    for name, reading in READINGS.items():
        rows = reading_rows(measured, name)
        tnc, tnc_by = _counts(rows, "tnc_within")
        ts, ts_by = _counts(rows, "ts_within")
        ahead[name] = ahead_claims(rows)
        figures[name] = check_claims(reading_cases(results, name)) if with_figures else []
        held = sum(a.holds for a in ahead[name])
        fig = f"{sum(c.holds for c in figures[name])}/{len(figures[name])}" if with_figures else ""
        lines.append(
            f"| {name} | {reading.label()} | {tnc} | {ts} | {tnc_by} | {ts_by} | "
            f"{held}/{len(ahead[name])} | {fig} |"
        )
    names = list(READINGS)
    lines += ["", "| claim | " + " | ".join(names) + " |", "|---|" + "---|" * len(names)]
    for k, first in enumerate(ahead[names[0]]):
        cells = []
        for name in names:
            a = ahead[name][k]
            digits = ".3f" if a.metric == "T_nc" else ".0f"
            verdict = "yes" if a.holds else "**no**"
            cells.append(f"{verdict} ({a.mdm:{digits}} vs {a.theirs:{digits}})")
        lines.append(f"| {first.claim} | " + " | ".join(cells) + " |")
    for k, claim in enumerate(figures[names[0]]):
        cells = ["yes" if figures[n][k].holds else "**no**" for n in names]
        lines.append(f"| {claim.figure}: {claim.text} | " + " | ".join(cells) + " |")
    return [*lines, ""]
