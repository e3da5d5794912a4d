"""The cases of section IV: which profile and method each table row needs, and the tolerances."""

from __future__ import annotations

from dataclasses import dataclass, replace

from mdm_montecarlo.study.paper import PaperRow, paper_rows
from mdm_montecarlo.study.variants import (
    LAWNMOWER_METHODS,
    SWARM_METHODS,
    with_fleet_size,
    with_method,
)
from mdm_profiles import MissionProfile, builtin_profile
from mdm_profiles.overrides import apply_overrides

TABLES = (
    "simtable1",
    "simtable3",
    "simtable4",
    "simtable5",
    "Dsimtable6",
    "simtablef1",
    "simtablepso1",
    "scaling",
    "section3b",
)
"""Tables `reproduce` knows. 'scaling' is the 6/12/24-UAV figures of Figs. 4-9 (box plots, no
printed numbers); 'section3b' is one UAV searching the fixed targets with US and with MDM,
set beside P_CS and P_CM of eqs. (18)-(22)."""

TNC_TOLERANCE = {"fixed": 0.05, "popup": 0.10, "dynamic": 0.10}
"""Relative tolerance on mean T_nc by scenario."""
TS_TOLERANCE = 0.15
"""Relative tolerance on mean T_S."""
SCALING_FLEETS = (6, 12, 24)
SECTION3B_METHODS = ("US", "MDM:LS+BS")
"""Single-sensor and MDM search of one UAV, for P_CS and P_CM."""
_FORGET = ("policy.swarm.after_confirmation=forget", "policy.swarm.read_confirmed=false")
_POPUP_FROM_0 = tuple(f"targets.{k}.appear={200 * k}" for k in range(10))
_LEAVE = ("target_motion.boundary=free", "mission.ts_rule=confirmed_or_gone")
_RENEW = "policy.redetection=renew"
VARIANTS: dict[str, tuple[str, tuple[str, ...]]] = {
    "eq10": (
        "eq. (10) literal",
        ("policy.waypoint_origin=position",),
    ),
    "popup_from_0": ("t_i = 200 (i - 1)", _POPUP_FROM_0),
    "targets_leave": ("targets leave, T_S confirmed or gone", _LEAVE),
    "renew": ("level 2 renewed by detections", (_RENEW,)),
    "popup_from_0_renew": (
        "t_i = 200 (i - 1), level 2 renewed by detections",
        (*_POPUP_FROM_0, _RENEW),
    ),
    "targets_leave_renew": (
        "targets leave, T_S confirmed or gone, level 2 renewed by detections",
        (*_LEAVE, _RENEW),
    ),
    "swarm_forgets": ("memory forgets confirmed targets", _FORGET),
    "lawnmower": ("lawnmower baseline, not in the paper: no paper value", ()),
    "swarm_waypoint_detection": (
        "waypoint PSO, MDM's detection sensor",
        ("policy.swarm.signal_sensor=detection", *_FORGET),
    ),
    "swarm_detection": (
        "swarm given MDM's detection sensor",
        (
            "policy.swarm.iteration=interval",
            "policy.swarm.signal_sensor=detection",
            *_FORGET,
        ),
    ),
}
"""Rows that fly a documented deviation of the defaults, beside the default row and the same
paper figures: name -> (label, profile overrides). 'eq10': level-2 waypoints step from the
previous waypoint, P_{q+1} = P_q + delta_2 D (the default steps from the point of detection;
docs/model.md, "Level-2 waypoints: the default is not eq. (10)"). 'popup_from_0': the pop-up
targets appear from t = 0 (docs/model.md, "Pop-up times"). 'targets_leave': the walk leaves
the area and T_S counts a target at its confirmation or its departure (docs/model.md,
"Targets that leave the area"). 'renew', 'popup_from_0_renew' and 'targets_leave_renew': the
default, 'popup_from_0' and 'targets_leave' with policy.redetection = renew (docs/model.md, "Level 2
renewed by detections"), flown for MDM only (a single-sensor search has no level 2). The swarm readings of
docs/model.md, "Social-cognitive baselines": 'swarm_forgets' drops the bests of confirmed
targets and does not read them; 'swarm_waypoint_detection' also reads MDM's 2 km detection
sensor; 'swarm_detection' is "swarm given MDM's detection sensor" (one iteration every 5 s,
100 m). 'lawnmower': the partitioned lawnmowers LM1/LM2 (docs/model.md, "The lawnmower
baseline"), which the paper does not fly: their rows carry no paper value."""
SWARM_VARIANTS = ("swarm_forgets", "swarm_waypoint_detection", "swarm_detection")
LEAVE_VARIANT_TABLES = ("simtable1", "simtablef1", "Dsimtable6", "simtable3", "scaling")
"""Tables whose dynamic rows (swarms aside) each have a 'targets_leave' row after them."""
POPUP_VARIANT_TABLES = ("simtable1", "simtablef1", "simtable3", "simtable5")
"""Tables whose pop-up rows (US, BS, LS and MDM) each have a 'popup_from_0' row after them."""
ALL_METHODS = ("US", "BS", "LS", "MDM")
RENEW_VARIANTS = {"fixed": "renew", "popup": "popup_from_0_renew", "dynamic": "targets_leave_renew"}
"""The renewed MDM row each scenario's MDM rows have after them (after the popup_from_0 and
targets_leave rows where those are flown): the choices of the 'closest' reading."""
LAWNMOWER_TABLES = ("simtable1", "simtablef1")
"""Tables that get LM1 and LM2 rows after each scenario's MDM row."""


@dataclass(frozen=True)
class Case:
    """One simulated configuration; several table rows may share it."""

    scenario: str
    method: str
    """'US', 'BS', 'LS' or 'MDM:<L1>+<L2>'."""
    delta1_pct: float
    n_uav: int
    n_false: int
    variant: str = ""
    """A key of VARIANTS, or '' for the defaults."""

    def profile(self) -> MissionProfile:
        base = builtin_profile(f"paper-{self.scenario}" + ("-false" if self.n_false else ""))
        delta1 = self.delta1_pct / 100.0 * base.area.north
        profile = with_fleet_size(with_method(base, self.method, delta1), self.n_uav)
        if self.method in SWARM_METHODS:
            # The paper prints no T_S for the swarm baselines: simulate up to the duration only.
            mission = profile.mission.model_copy(update={"ts_cap": profile.mission.duration})
            profile = profile.model_copy(update={"mission": mission})
        if self.variant:
            profile = apply_overrides(profile, list(VARIANTS[self.variant][1]))
        return profile


@dataclass(frozen=True)
class Row:
    """A row to report: the table it belongs to, its case, and the paper's numbers if printed."""

    table: str
    case: Case
    paper: PaperRow | None


def _case_of(row: PaperRow) -> Case:
    method = f"MDM:{row.level1}+{row.level2}" if row.method == "MDM" else row.method
    return Case(row.scenario, method, row.delta1_pct_L or 20.0, row.n_uav, row.n_false)


def _renewed_here(row: PaperRow) -> bool:
    """Whether the MDM row has a renewed row: fixed everywhere; pop-up and dynamic in the tables
    whose rows also fly popup_from_0 and targets_leave (the reading's other choices)."""
    if row.scenario == "popup":
        return row.table in POPUP_VARIANT_TABLES
    if row.scenario == "dynamic":
        return row.table in LEAVE_VARIANT_TABLES
    return row.scenario == "fixed"


def study_rows(tables: tuple[str, ...] = TABLES) -> list[Row]:
    """Rows of the requested tables, in the paper's order."""
    unknown = set(tables) - set(TABLES)
    if unknown:
        raise ValueError(f"unknown table(s) {sorted(unknown)}; allowed: {', '.join(TABLES)}")
    rows: list[Row] = []
    for r in paper_rows():
        if r.table not in tables:
            continue
        rows.append(Row(r.table, _case_of(r), r))
        if r.table == "simtable1" and r.method == "MDM":
            rows.append(Row(r.table, replace(_case_of(r), variant="eq10"), r))
        if r.table in POPUP_VARIANT_TABLES and r.scenario == "popup" and r.method in ALL_METHODS:
            rows.append(Row(r.table, replace(_case_of(r), variant="popup_from_0"), r))
        if r.table in LEAVE_VARIANT_TABLES and r.scenario == "dynamic" and r.method in ALL_METHODS:
            rows.append(Row(r.table, replace(_case_of(r), variant="targets_leave"), r))
        if r.method == "MDM" and _renewed_here(r):
            rows.append(Row(r.table, replace(_case_of(r), variant=RENEW_VARIANTS[r.scenario]), r))
        if r.table in LAWNMOWER_TABLES and r.method == "MDM":
            rows += [
                Row(r.table, replace(_case_of(r), method=m, variant="lawnmower"), None)
                for m in LAWNMOWER_METHODS
            ]
        if r.table == "simtablepso1" and r.method in SWARM_METHODS:
            rows += [Row(r.table, replace(_case_of(r), variant=v), r) for v in SWARM_VARIANTS]
    if "scaling" in tables:
        best = {"fixed": "MDM:LS+BS", "popup": "MDM:US+US", "dynamic": "MDM:LS+BS"}
        for scenario, mdm in best.items():
            for n in SCALING_FLEETS:
                for method in ("US", "BS", "LS", mdm):
                    case = Case(scenario, method, 20.0, n, 0)
                    rows.append(Row("scaling", case, None))
                    if scenario == "dynamic":
                        rows.append(Row("scaling", replace(case, variant="targets_leave"), None))
    if "section3b" in tables:
        for method in SECTION3B_METHODS:
            rows.append(Row("section3b", Case("fixed", method, 20.0, 1, 0), None))
    return rows
