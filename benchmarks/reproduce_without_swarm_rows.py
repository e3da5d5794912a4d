"""`mdm-montecarlo reproduce` without the swarm readings' rows added beside the paper's: the 27
waypoint rows (PSO, SPSO, ARPSO x three scenarios in the text's reading, "forgets" and
"waypoint, r_1") and the 2 pop-up rows "t_i = 200 (i - 1)". What is left are the 98
configurations that reproduce ran before them (the interval swarm rows included), so timing
this beside the full command gives what those rows cost:

    /usr/bin/time -f "%e s wall, %U+%S CPU-s" .venv/bin/mdm-montecarlo reproduce --runs 1000 --workers 2 --out /tmp/a --no-progress
    /usr/bin/time -f "%e s wall, %U+%S CPU-s" .venv/bin/python benchmarks/reproduce_without_swarm_rows.py reproduce --runs 1000 --workers 2 --out /tmp/b --no-progress

Every argument is reproduce's; only the rows differ.
"""

from __future__ import annotations

import sys

from mdm_montecarlo.commands import cli
from mdm_montecarlo.study import cases
from mdm_montecarlo.study.cases import Row
from mdm_montecarlo.study.variants import SWARM_METHODS


def rows_before(tables: tuple[str, ...] = cases.TABLES) -> list[Row]:
    """study_rows without the waypoint swarm rows and the 'popup_from_0' rows."""
    return [
        row
        for row in cases.study_rows(tables)
        if row.case.variant != "popup_from_0"
        and (row.case.method not in SWARM_METHODS or row.case.variant == "swarm_detection")
    ]


if __name__ == "__main__":
    cli.study_rows = rows_before  # type: ignore[attr-defined]
    sys.exit(cli.main(sys.argv[1:]))
