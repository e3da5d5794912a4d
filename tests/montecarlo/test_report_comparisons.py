"""The report's section of MDM against the best single sensor and the swarms."""

from __future__ import annotations

import re

import pytest

from mdm_montecarlo.engines.runner import run_many
from mdm_montecarlo.study.cases import study_rows
from mdm_montecarlo.study.report_comparisons import comparison_section


def test_mdm_is_set_against_the_best_single_sensor_and_every_swarm() -> None:
    rows = [
        r
        for r in study_rows(("simtable1", "simtablepso1"))
        if r.case.scenario == "fixed" and not r.case.variant
    ]
    cases = list(dict.fromkeys(r.case for r in rows))
    results = dict(
        zip(cases, run_many([c.profile() for c in cases], runs=300, seed=4), strict=True)
    )
    lines = comparison_section(rows, results)
    table = [line.split(" | ") for line in lines if line.startswith("| simtable")]
    single = {c.method: results[c].tnc.mean() for c in cases if c.method in ("US", "BS", "LS")}
    best = max(single, key=lambda m: single[m])
    against = [(cells[0], cells[3], cells[4]) for cells in table]
    assert against == [
        ("| simtable1", best, "T_nc"),
        ("| simtable1", best, "T_S"),
        ("| simtablepso1", "PSO", "T_nc"),
        ("| simtablepso1", "SPSO", "T_nc"),
        ("| simtablepso1", "ARPSO", "T_nc"),
    ]
    mdm = next(c for c in cases if c.method.startswith("MDM"))
    first = table[0]
    assert float(first[5]) == pytest.approx(results[mdm].tnc.mean(), abs=5e-4)
    assert float(first[7]) == pytest.approx(results[mdm].tnc.mean() - single[best], abs=5e-4)
    low, high = map(float, re.findall(r"-?\d+\.\d+", first[8]))
    assert low < float(first[7]) < high


def test_no_compared_table_no_section() -> None:
    rows = study_rows(("simtable4",))
    assert comparison_section(rows, {}) == []
