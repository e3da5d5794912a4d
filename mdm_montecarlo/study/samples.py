"""Per-run samples: every run's outcome as rows of two tables, written as Parquet and CSV.

``runs``: one row per run, the values every aggregate of a report is computed from
(T_nc, T_S and whether it was capped; AISE and AISC are differences of their means).
``confirmations``: one row per target a run's team confirmed, with the time and the vehicle
that confirmed it first. Both start with the configuration's columns (``config`` and what
the writer adds: scenario, method, the swept values...; the confirmations only ``config``).
The columns: docs/study.md.

pyarrow is imported where a table is written or read, not with this module: the
simulation workers `reproduce` forks import the module and never write.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from mdm_montecarlo.engines.runner import MissionResults

if TYPE_CHECKING:
    import pyarrow as pa

RUNS = "samples-runs"
CONFIRMATIONS = "samples-confirmations"
PROVENANCE_KEY = b"mdm_provenance"
"""Parquet schema metadata key: the provenance record (JSON) of the command that wrote it."""
ConfigColumns = Mapping[str, str | int | float]


@dataclass(frozen=True)
class RunOutcomes:
    """The per-run values of one configuration's runs (what its aggregates are computed from)."""

    tnc: NDArray[np.int64]
    ts: NDArray[np.float64] | None
    """None where the runs stopped at the mission duration (the swarms: no T_S)."""
    ts_capped: NDArray[np.bool_] | None


def run_outcomes(res: MissionResults) -> RunOutcomes:
    if not res.has_ts:
        return RunOutcomes(res.tnc, None, None)
    ts, capped = res.ts()
    return RunOutcomes(res.tnc, ts, capped)


def run_columns(res: MissionResults) -> dict[str, NDArray[np.generic]]:
    """One row per run: its identity (seed, block, place in block), T_nc, T_S, capped, and
    how many false targets its team confirmed."""
    out = run_outcomes(res)
    runs = res.runs
    false = ~res.real
    nan = np.full(runs, np.nan)
    return {
        "run": np.arange(runs, dtype=np.int64),
        "seed": np.full(runs, res.seed, dtype=np.int64),
        "block": res.run_block,
        "run_in_block": res.run_in_block,
        "tnc": out.tnc,
        "ts_s": nan if out.ts is None else out.ts,
        "ts_capped": np.zeros(runs, bool) if out.ts_capped is None else out.ts_capped,
        "has_ts": np.full(runs, out.ts is not None),
        "false_confirmations": np.isfinite(res.team_times[:, false]).sum(axis=1).astype(np.int64),
        "targets": np.full(runs, res.team_times.shape[1], dtype=np.int64),
        "mission_duration_s": np.full(runs, res.profile.mission.duration),
    }


def confirmation_columns(res: MissionResults) -> dict[str, NDArray[np.generic]]:
    """One row per (run, target) the team confirmed: time, first vehicle, false target or not,
    and whether it counts in T_nc (confirmed by the mission duration)."""
    run, target = np.nonzero(np.isfinite(res.team_times))
    time = res.team_times[run, target]
    return {
        "run": run.astype(np.int64),
        "target": target.astype(np.int64),
        "time_s": time,
        "vehicle": res.first_vehicle[run, target].astype(np.int64),
        "false_target": ~res.real[target],
        "within_duration": time <= res.profile.mission.duration,
    }


def _table(
    parts: Sequence[tuple[ConfigColumns, dict[str, NDArray[np.generic]]]],
) -> pa.Table:
    import pyarrow as pa

    pieces = []
    for config, columns in parts:
        n = len(next(iter(columns.values())))
        head = {key: pa.repeat(pa.scalar(value), n) for key, value in config.items()}
        pieces.append(pa.table({**head, **{k: pa.array(v) for k, v in columns.items()}}))
    return pa.concat_tables(pieces, promote_options="permissive")


def sample_tables(configs: Sequence[tuple[ConfigColumns, MissionResults]]) -> dict[str, pa.Table]:
    """The runs and confirmations tables of the configurations (by file stem); every config
    mapping needs the same keys. The confirmations carry only the ``config`` label of them
    (with ``run``, the key into the runs table): a full `reproduce` confirms a million
    targets, and the other columns there were a third of a 113 MB CSV."""
    return {
        RUNS: _table([(config, run_columns(res)) for config, res in configs]),
        CONFIRMATIONS: _table(
            [({"config": config["config"]}, confirmation_columns(res)) for config, res in configs]
        ),
    }


def write_tables(
    folder: Path, tables: Mapping[str, pa.Table], provenance: Mapping[str, object]
) -> list[Path]:
    """Each table as STEM.parquet (the provenance in its schema metadata) and STEM.csv."""
    import pyarrow.csv as pa_csv
    import pyarrow.parquet as pq

    written = []
    meta = {PROVENANCE_KEY: json.dumps(dict(provenance), default=str).encode()}
    for name, table in tables.items():
        pq.write_table(table.replace_schema_metadata(meta), folder / f"{name}.parquet")
        pa_csv.write_csv(table, folder / f"{name}.csv")
        written += [folder / f"{name}.parquet", folder / f"{name}.csv"]
    return written


def write_samples(
    folder: Path,
    configs: Sequence[tuple[ConfigColumns, MissionResults]],
    provenance: Mapping[str, object],
) -> list[Path]:
    """samples-runs and samples-confirmations (.parquet and .csv) of the configurations."""
    return write_tables(folder, sample_tables(configs), provenance)


def read_runs(folder: Path) -> pa.Table:
    """The runs table of a results folder; a ValueError naming the folder if it has none."""
    import pyarrow.parquet as pq

    path = folder / f"{RUNS}.parquet"
    if not path.is_file():
        raise ValueError(f"{folder}: no {RUNS}.parquet (not a results folder of mdm-montecarlo)")
    return pq.read_table(path)


def read_provenance(path: Path) -> dict[str, object]:
    """The provenance record stored in a samples Parquet file."""
    import pyarrow.parquet as pq

    meta = pq.read_schema(path).metadata or {}
    if PROVENANCE_KEY not in meta:
        raise ValueError(f"{path}: no provenance in its metadata")
    record: dict[str, object] = json.loads(meta[PROVENANCE_KEY])
    return record
