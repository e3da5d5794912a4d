"""What `run`, `reproduce` and `sweep` leave beside their tables: the per-run samples
(samples.py), provenance.json, and the provenance block at the end of report.md."""

from __future__ import annotations

import json
import tempfile
from collections.abc import Sequence
from pathlib import Path

from mdm_montecarlo.engines.runner import MissionResults
from mdm_montecarlo.study.cases import Case
from mdm_montecarlo.study.samples import ConfigColumns, write_samples
from mdm_provenance import Provenance

PROVENANCE_FILE = "provenance.json"
PROVENANCE_HEADING = "## Provenance"


def case_columns(case: Case) -> dict[str, str | int | float]:
    """The configuration columns of a study case in the samples tables."""
    variant = f" [{case.variant}]" if case.variant else ""
    return {
        "config": f"{case.scenario} {case.method} d1={case.delta1_pct:g}% "
        f"uav={case.n_uav} false={case.n_false}{variant}",
        "scenario": case.scenario,
        "method": case.method,
        "delta1_pct": float(case.delta1_pct),
        "n_uav": case.n_uav,
        "n_false": case.n_false,
        "variant": case.variant,
    }


def check_writable(folder: Path) -> None:
    """Fail before any simulation if the report folder cannot be created or written."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        raise ValueError(f"--out {folder}: not a writable folder ({exc.strerror or exc})") from None


def write_result_files(
    folder: Path, configs: Sequence[tuple[ConfigColumns, MissionResults]], record: Provenance
) -> list[Path]:
    """The samples (Parquet with the record in its metadata, and CSV) and provenance.json."""
    folder.mkdir(parents=True, exist_ok=True)
    written = write_samples(folder, configs, record.as_dict())
    path = folder / PROVENANCE_FILE
    path.write_text(json.dumps(record.as_dict(), indent=2) + "\n", encoding="utf-8")
    return [*written, path]


def append_provenance(report: Path, record: Provenance) -> None:
    """End report.md with its provenance: a heading and one JSON block."""
    block = json.dumps(record.as_dict(), indent=2)
    with report.open("a", encoding="utf-8") as fh:
        fh.write(f"\n{PROVENANCE_HEADING}\n\n```json\n{block}\n```\n")


def report_provenance(report: Path) -> dict[str, object]:
    """The provenance block of a report.md, parsed; a ValueError naming the file if absent."""
    text = report.read_text(encoding="utf-8")
    _, heading, rest = text.partition(f"\n{PROVENANCE_HEADING}\n")
    start = rest.find("```json\n")
    end = rest.find("\n```", start + 8)
    if not heading or start < 0 or end < 0:
        raise ValueError(f"{report}: no '{PROVENANCE_HEADING}' JSON block")
    record: dict[str, object] = json.loads(rest[start + 8 : end])
    return record
