"""Why a reproduced row lies outside the paper's tolerance: its docs/model.md entry and the
closest variant we measured (value, runs and how to re-run it are in that entry).

Each cause matches rows by table, scenario, method and metric; the first match wins. The
headings named here are checked against docs/model.md by tests/montecarlo/test_report.py.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass

from mdm_montecarlo.study.cases import VARIANTS
from mdm_montecarlo.study.tables import MeasuredRow

SWARMS = ("PSO", "SPSO", "ARPSO")
_WAYPOINT_R1 = "waypoint PSO, MDM's detection sensor"
_CLOSEST_SWARM = {
    ("fixed", "PSO"): (_WAYPOINT_R1, 4.496),
    ("fixed", "SPSO"): (_WAYPOINT_R1, 4.547),
    ("fixed", "ARPSO"): (_WAYPOINT_R1, 4.353),
    ("popup", "PSO"): ("the text's reading (default)", 2.896),
    ("popup", "SPSO"): ("the text's reading (default)", 3.279),
    ("popup", "ARPSO"): ("the text's reading (default)", 3.182),
    ("dynamic", "PSO"): (_WAYPOINT_R1, 4.319),
    ("dynamic", "SPSO"): (_WAYPOINT_R1, 4.504),
    ("dynamic", "ARPSO"): (_WAYPOINT_R1, 4.236),
}
"""The swarm reading of `reproduce` whose T_nc is closest to the paper's, with its T_nc: 1000
runs, seed 2024 (docs/model.md, "simtablepso1 at 1000 runs, every reading")."""
_REFLECT_DELTA1 = {10.0: 3.69, 20.0: 4.21, 30.0: 4.25, 40.0: 4.34, 50.0: 4.65}
"""simtable3 fixed MDM T_nc with out_of_area = reflect, 300 runs (docs/model.md)."""


@dataclass(frozen=True)
class Cause:
    heading: str
    """The docs/model.md heading (## or ###) that explains the rows."""
    matches: Callable[[MeasuredRow, str], bool]
    """(row, metric 'T_nc' or 'T_S') -> does this cause apply."""
    closest: Callable[[MeasuredRow, str], str]
    """The closest measured variant and its value, as text."""

    @property
    def anchor(self) -> str:
        return slug(self.heading)


def slug(heading: str) -> str:
    """The anchor GitHub gives a Markdown heading."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


_LEAVING = {VARIANTS[k][0] for k in ("targets_leave", "targets_leave_renew")}
_FROM_0 = {VARIANTS[k][0] for k in ("popup_from_0", "popup_from_0_renew")}
"""The variant rows of those two readings, with MDM's renewed ones (the 'closest' reading's);
the fixed renewed rows take the causes of their table and scenario."""


def _is_mdm(row: MeasuredRow) -> bool:
    return row.method == "MDM"


CAUSES: tuple[Cause, ...] = (
    Cause(
        "Level-2 waypoints: the default is not eq. (10)",
        lambda r, m: r.variant == VARIANTS["eq10"][0],
        lambda r, m: "the default rule (anchor) is the row above it",
    ),
    Cause(
        "Targets that leave the area",
        lambda r, m: r.variant in _LEAVING,
        lambda r, m: "the default (bounce, confirmations only) is a row above it",
    ),
    Cause(
        "Social-cognitive baselines (PSO, SPSO, ARPSO; simtablepso1)",
        lambda r, m: r.method in SWARMS,
        lambda r, m: "{} {:.3f}".format(
            *_CLOSEST_SWARM.get((r.scenario, r.method), ("none measured", float("nan")))
        ),
    ),
    Cause(
        "Fall-backs, sensor memory and C_I(0)",
        lambda r, m: (
            m == "T_S"
            and _is_mdm(r)
            and r.scenario == "fixed"
            and r.n_false == 0
            and r.delta1_pct_L == 20.0
        ),
        lambda r, m: "detection_memory = exact: 4623 s (LS+BS, 1000 runs)",
    ),
    Cause(
        "Pop-up times",
        lambda r, m: r.variant in _FROM_0,
        lambda r, m: "the default appear times (t_i = 200 i) are a row above it",
    ),
    Cause(
        "Pop-up times",
        lambda r, m: r.scenario == "popup" and m == "T_nc",
        lambda r, m: "appear times t_i = 200 (i - 1): US 4.237, MDM US+US 4.937 (300 runs)",
    ),
    Cause(
        "Pop-up times",
        lambda r, m: r.scenario == "popup" and m == "T_S",
        lambda r, m: "none measured comes closer",
    ),
    Cause(
        "Dynamic targets: the boundary rule",
        lambda r, m: r.scenario == "dynamic" and m == "T_S",
        lambda r, m: "memory by target identity (engine experiment): MDM LS+BS 6117 s (400 runs)",
    ),
    Cause(
        "Dynamic targets: the boundary rule",
        lambda r, m: r.scenario == "dynamic",
        lambda r, m: "no open choice moves MDM's dynamic T_nc further in (kappa 130: 3.992)",
    ),
    Cause(
        "Step length delta1 (simtable3)",
        lambda r, m: r.table == "simtable3",
        lambda r, m: (
            f"out_of_area = reflect: {_REFLECT_DELTA1[r.delta1_pct_L]:.2f} (300 runs)"
            if m == "T_nc" and r.delta1_pct_L in _REFLECT_DELTA1
            else "none measured comes closer"
        ),
    ),
    Cause(
        "Levy step lengths (simtable4)",
        lambda r, m: r.table == "simtable4",
        lambda r, m: "none measured: every variant raises these rows",
    ),
    Cause(
        "False targets (simtablef1)",
        lambda r, m: r.n_false > 0,
        lambda r, m: "none measured",
    ),
    Cause(
        "simtable1 at 1000 runs (measured)",
        lambda r, m: m == "T_S" and not _is_mdm(r),
        lambda r, m: "out_of_area = clip: US T_S 8811 s, but T_nc 2.745 (200 runs)",
    ),
    Cause(
        "The open choices",
        lambda r, m: True,
        lambda r, m: "not analysed",
    ),
)


def cause_of(row: MeasuredRow, metric: str) -> Cause:
    """The first cause that applies to ``metric`` ('T_nc' or 'T_S') of ``row``."""
    return next(c for c in CAUSES if c.matches(row, metric))
