"""The reproduce report: summary first, causes linked to docs/model.md, section III-B, the
claims about Figs. 4-9, and the eq. (10) row."""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from mdm_montecarlo.engines.runner import MissionResults, run_many
from mdm_montecarlo.study.cases import RENEW_VARIANTS, Case, Row, study_rows
from mdm_montecarlo.study.known_causes import CAUSES, slug
from mdm_montecarlo.study.report import write_report
from mdm_montecarlo.study.section3b import SearchGeometry, confirmed_share, p_cm, p_cm_given, p_cs
from mdm_montecarlo.study.tables import format_table, measured_rows
from mdm_profiles.overrides import apply_overrides

MODEL = Path(__file__).resolve().parents[2] / "docs" / "model.md"
PAPER = SearchGeometry(area=4e8, speed=20.0, confirm_radius=400.0, detect_radius=2000.0)


def test_every_cause_names_a_heading_of_docs_model_md() -> None:
    anchors = {slug(h) for h in re.findall(r"^#{2,3} (.+)$", MODEL.read_text(), re.MULTILINE)}
    for cause in CAUSES:
        assert cause.anchor in anchors, cause.heading


def test_p_cs_and_p_cm_follow_eqs_18_to_20() -> None:
    t = np.array([0.0, 1000.0, 10_000.0])
    rate = 2 * 400.0 * 20.0 / 4e8
    np.testing.assert_allclose(p_cs(t, PAPER), 1 - np.exp(-rate * t))
    # Before t_d both are the same (eq. 20); after it MDM searches the r_1 disc (eq. 19).
    given = p_cm_given(t, np.array(1000.0), PAPER)
    assert given[1] == pytest.approx(p_cs(t, PAPER)[1])
    disc_rate = 2 * 400.0 * 20.0 / (np.pi * 2000.0**2)
    expected = 1 - (1 - p_cs(np.array(1000.0), PAPER)) * np.exp(-disc_rate * 9000.0)
    assert given[2] == pytest.approx(expected)
    # Eq. (22) holds for the averaged curve too.
    grid = np.linspace(0.0, 40_000.0, 41)
    assert (p_cm(grid, PAPER) >= p_cs(grid, PAPER) - 1e-12).all()


def test_one_uav_single_sensor_search_follows_eq_18() -> None:
    """The engine's US search by one UAV confirms a given target at about the rate of the
    random-search law (fixed seed; a wrong sensor radius or speed would double or halve it)."""
    (res,) = run_many([Case("fixed", "US", 20.0, 1, 0).profile()], runs=300, seed=4)
    t = np.array([5000.0, 10_000.0, 20_000.0])
    share = confirmed_share(res.team_times, t)
    print("simulated", share, "eq. (18)", p_cs(t, PAPER))
    np.testing.assert_allclose(share, p_cs(t, PAPER), atol=0.06)


Flown = tuple[list[Row], dict[Case, MissionResults]]


@pytest.fixture(scope="module")
def small_study() -> Flown:
    rows = study_rows(("simtable1", "section3b"))
    cases = list(dict.fromkeys(r.case for r in rows))
    results = dict(zip(cases, run_many([c.profile() for c in cases], runs=40, seed=1), strict=True))
    return rows, results


@pytest.fixture(scope="module")
def small_report(tmp_path_factory: pytest.TempPathFactory, small_study: Flown) -> str:
    rows, results = small_study
    folder = tmp_path_factory.mktemp("report")
    path = write_report(folder, rows, measured_rows(rows, results), results, "header line")
    for png in ("simtable1-fixed.png", "section3b-pcs-pcm.png"):
        assert (folder / png).stat().st_size > 10_000
    return path.read_text()


def test_summary_comes_first_and_outside_rows_link_their_cause(small_report: str) -> None:
    assert small_report.index("## Summary") < small_report.index("## simtable1")
    assert re.search(r"T_nc inside tolerance: \d+ of 12 rows", small_report)  # the reading's
    outside = small_report.split("## Means outside tolerance")[1].split("\n## ", maxsplit=1)[0]
    rows = [line for line in outside.splitlines() if line.startswith("| simtable1")]
    assert rows
    for line in rows:
        assert re.search(r"\]\([^)]*model\.md#[a-z0-9_-]+\)", line), line
        assert line.rstrip("| ").split("|")[-1].strip(), line  # a closest variant is named


def test_eq10_row_sits_beside_the_default(small_report: str) -> None:
    table = small_report.split("## simtable1")[1]
    lines = [ln for ln in table.splitlines() if ln.startswith("| simtable1 | fixed | MDM")]
    assert [("eq. (10) literal" in ln) for ln in lines] == [False, True, False]
    assert "level 2 renewed by detections" in lines[2]  # the renewed row after both


def test_popup_rows_from_t0_follow_the_default_rows(small_report: str) -> None:
    """Every pop-up row (US, BS, LS, MDM) with t_i = 200 (i - 1) comes after its default row
    (MDM's after its eq. (10) row) and flies targets that appear from t = 0."""
    table = small_report.split("## simtable1")[1]
    label = "t_i = 200 (i - 1)"
    expected = {"US": [False, True], "BS": [False, True], "LS": [False, True]}
    expected["MDM"] = [False, False, True, True]  # the last renewed as well
    for method, marks in expected.items():
        lines = [
            ln for ln in table.splitlines() if ln.startswith(f"| simtable1 | popup | {method}")
        ]
        assert [label in ln for ln in lines] == marks
    rows = study_rows(("simtable1",))
    variant = [r.case for r in rows if r.case.variant == "popup_from_0"]
    assert [c.method for c in variant] == ["US", "BS", "LS", "MDM:US+US"]
    appear = [t.appear for t in variant[0].profile().targets]
    assert appear == [200.0 * k for k in range(10)]


def test_every_popup_row_of_four_tables_has_its_t0_row() -> None:
    """simtablef1, simtable3 and simtable5: each pop-up row is followed by the same case with
    targets from t = 0 (simtablef1's false targets stay false); no other scenario has one."""
    rows = study_rows(("simtablef1", "simtable3", "simtable5"))
    for k, row in enumerate(rows):
        if row.case.variant == "popup_from_0":
            before = rows[k - 1].case
            assert row.case.scenario == "popup"
            assert row.case == replace(before, variant="popup_from_0")
            targets = row.case.profile().targets
            assert [t.appear for t in targets] == [200.0 * i for i in range(10)]
            assert [t.false_target for t in targets] == [
                t.false_target for t in before.profile().targets
            ]
    counts = {
        table: sum(r.case.variant == "popup_from_0" for r in rows if r.table == table)
        for table in ("simtablef1", "simtable3", "simtable5")
    }
    assert counts == {"simtablef1": 4, "simtable3": 5, "simtable5": 9}


def test_every_swarm_row_has_its_three_labelled_readings() -> None:
    """simtablepso1: each swarm row, then the same row in the three other readings, each
    flying its settings; the unlabelled row flies the text's reading (the defaults)."""
    rows = [r for r in study_rows(("simtablepso1",)) if not r.case.method.startswith("MDM")]
    assert len(rows) == 9 * 4
    for k in range(0, len(rows), 4):
        group = [r.case for r in rows[k : k + 4]]
        assert [c.variant for c in group] == [
            "",
            "swarm_forgets",
            "swarm_waypoint_detection",
            "swarm_detection",
        ]
        swarm = [c.profile().policy.swarm for c in group]
        readings = [
            (s.iteration, s.signal_sensor, s.after_confirmation, s.read_confirmed) for s in swarm
        ]
        assert readings == [
            ("waypoint", "confirmation", "keep", True),
            ("waypoint", "confirmation", "forget", False),
            ("waypoint", "detection", "forget", False),
            ("interval", "detection", "forget", False),
        ]


def test_section_3b_is_in_the_report(small_report: str) -> None:
    part = small_report.split("## Section III-B")[1]
    assert "![P_CS and P_CM](section3b-pcs-pcm.png)" in part
    assert len(re.findall(r"^\| \d+ \| 0\.\d{3} \|", part, re.MULTILINE)) == 5


def test_no_improvement_percentage_against_a_baseline_that_confirmed_nothing() -> None:
    # 60 s missions: nobody reaches a target, so AISE's baseline T_nc is 0 (as with --runs 1)
    rows = study_rows(("simtable1",))
    cases = list(dict.fromkeys(r.case for r in rows))
    short = ["mission.duration=60", "mission.ts_cap=60"]
    profiles = [apply_overrides(c.profile(), short) for c in cases]
    results = dict(zip(cases, run_many(profiles, runs=2, seed=1), strict=True))
    measured = measured_rows(rows, results)
    baselines = [m for m in measured if m.method != "MDM"]
    assert baselines
    assert all(m.tnc_mean == 0 for m in measured)
    assert all(m.aise_pct is None and m.aisc_pct is None for m in baselines)
    table = format_table(measured)
    assert "nan" not in table.lower()
    assert "inf" not in table.lower()


def test_every_mdm_row_has_its_renewed_row_after_its_other_readings() -> None:
    """Each MDM row of the paper's tables is followed (after its eq. (10), t_i = 200 (i - 1) and
    targets-leave rows) by the renewed row of its scenario, the 'closest' reading's first
    choice, flying policy.redetection = renew; the single-sensor rows have none."""
    rows = study_rows()
    renewed = [k for k, r in enumerate(rows) if r.case.variant in RENEW_VARIANTS.values()]
    assert renewed
    for k in renewed:
        case = rows[k].case
        assert case.method.startswith("MDM:")
        assert case.variant == RENEW_VARIANTS[case.scenario]
        d = max(j for j in range(k) if not rows[j].case.variant)  # its default row
        assert case == replace(rows[d].case, variant=case.variant)
        between = {r.case.variant for r in rows[d + 1 : k]}
        assert between <= {"eq10", "popup_from_0", "targets_leave"}, between
        assert case.profile().policy.redetection == "renew"
    fixed_mdm = [
        r
        for r in rows
        if r.paper is not None and r.case.method.startswith("MDM:") and r.case.scenario == "fixed"
    ]
    assert sum(not r.case.variant for r in fixed_mdm) == sum(
        r.case.variant == "renew" for r in fixed_mdm
    )


def test_every_dynamic_row_has_its_targets_leave_row() -> None:
    """simtable1, simtablef1, Dsimtable6, simtable3 and scaling: each dynamic row (swarms
    aside) is followed by the same case with the free walk and T_S counting departures."""
    tables = ("simtable1", "simtablef1", "Dsimtable6", "simtable3", "scaling")
    rows = study_rows(tables)
    leave = [k for k, r in enumerate(rows) if r.case.variant == "targets_leave"]
    dynamic = [r for r in rows if r.case.scenario == "dynamic" and not r.case.variant]
    assert len(leave) == len(dynamic) == 4 + 4 + 9 + 5 + 12
    for k in leave:
        # the default row before it (simtable1/f1's lawnmower rows may sit between them)
        before = next(r.case for r in reversed(rows[:k]) if not r.case.variant)
        assert rows[k].case == replace(before, variant="targets_leave")
        profile = rows[k].case.profile()
        assert profile.target_motion is not None
        assert profile.target_motion.boundary == "free"
        assert profile.mission.ts_rule == "confirmed_or_gone"


def test_the_readings_section_counts_the_chosen_variant_rows(small_report: str) -> None:
    """simtable1 alone: 'closest' takes the t_i = 200 (i - 1) row of each pop-up row (4 rows),
    so its T_nc rows are the default reading's 12, not 12 plus the variants."""
    part = small_report.split("## Readings")[1].split("\n## ", maxsplit=1)[0]
    default = next(ln for ln in part.splitlines() if ln.startswith("| default |"))
    closest = next(ln for ln in part.splitlines() if ln.startswith("| closest |"))
    assert re.search(r"\| \d+/12 \| \d+/12 \|", default)
    assert re.search(r"\| \d+/12 \| \d+/12 \|", closest)
    assert "popup: t_i = 200 (i - 1)" in closest


def test_the_closest_reading_heads_the_report_with_its_own_rows(
    tmp_path: Path, small_study: Flown, small_report: str
) -> None:
    """--reading closest: the summary counts the rows of the Readings table's 'closest' line
    (its pop-up rows from t = 0), the default report the 'default' line's; the claims table
    gives MDM's lead under both, and the rows outside under closest are listed with a cause."""
    rows, results = small_study
    measured = measured_rows(rows, results)
    path = write_report(tmp_path, rows, measured, results, "header", reading="closest")
    closest = path.read_text()
    for text, name in ((small_report, "default"), (closest, "closest")):
        head = re.search(r"T_nc inside tolerance: (\d+) of (\d+) rows; T_S: (\d+) of (\d+)", text)
        assert head is not None
        line = next(ln for ln in text.splitlines() if ln.startswith(f"| {name} |"))
        cells = [c.strip() for c in line.split("|")]
        assert cells[3:5] == [f"{head[1]}/{head[2]}", f"{head[3]}/{head[4]}"], line
        assert f"Reading `{name}`" in text
    claims = [ln for ln in closest.splitlines() if re.match(r"\| simtable1 \w+: MDM ahead", ln)]
    assert len(claims) == 3 * 3 * 2  # three scenarios, US/BS/LS, T_nc and T_S
    pop = next(ln for ln in claims if ln.startswith("| simtable1 popup: MDM ahead of US in T_nc"))
    # the default cell compares the default rows, the closest cell the t_i = 200 (i - 1) rows,
    # MDM's renewed as well
    mdm = [m for m in measured if m.scenario == "popup" and m.method == "MDM"]
    us = [m for m in measured if m.scenario == "popup" and m.method == "US"]
    assert us[-1].variant == "t_i = 200 (i - 1)"
    assert mdm[-1].variant == "t_i = 200 (i - 1), level 2 renewed by detections"
    assert f"{mdm[0].tnc_mean:.3f} vs {us[0].tnc_mean:.3f}" in pop.split("|")[2]
    assert f"{mdm[-1].tnc_mean:.3f} vs {us[-1].tnc_mean:.3f}" in pop.split("|")[3]
    outside = closest.split("## Outside under closest")[1].split("\n## ", maxsplit=1)[0]
    popup = [ln for ln in outside.splitlines() if ln.startswith("| simtable1 popup")]
    assert popup
    assert all("t_i = 200 (i - 1)" in ln and "model.md#" in ln for ln in popup)
