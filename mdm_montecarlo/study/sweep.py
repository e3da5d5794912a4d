"""A parameter sweep: one profile and method flown at every combination of the values given
for some profile fields (the cartesian product), each combination a point of ``runs`` runs.

Every point uses the same master seed, so its runs see the same targets and start points as
the other points' (common random numbers: the differences along the sweep are the
parameter's, not the draws'); results are identical for any number of workers or on Dask,
as `reproduce`'s. A sweep's folder keeps each finished point's samples under points/; the
same command again goes on from the first point not yet done (sweep.json records what was
asked, and another ask in the same folder is refused).
"""

from __future__ import annotations

import itertools
import json
import os
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from mdm_montecarlo.engines.runner import MissionResults, RunInterruptedError, run_many
from mdm_montecarlo.study.samples import CONFIRMATIONS, RUNS, sample_tables
from mdm_montecarlo.study.variants import with_method
from mdm_profiles import MissionProfile, ProfileError
from mdm_profiles.overrides import apply_overrides

if TYPE_CHECKING:
    import pyarrow as pa

ASK_FILE = "sweep.json"
POINTS = "points"


@dataclass(frozen=True)
class SweepAsk:
    """What a sweep computes; a folder holds the points of one ask only."""

    profile: str
    method: str | None
    overrides: list[str]
    vary: list[tuple[str, list[str]]]
    """(profile field as in --set, its values as given), in the order of --vary."""
    runs: int
    seed: int

    def as_dict(self) -> dict[str, object]:
        return asdict(self)


@dataclass(frozen=True)
class Point:
    index: int
    values: tuple[str, ...]
    """One value per varied field, in the ask's order."""
    profile: MissionProfile


def parse_vary(items: list[str]) -> list[tuple[str, list[str]]]:
    """'KEY=V1,V2,...' per --vary -> [(KEY, [V1, V2, ...])]; a ValueError naming the item."""
    out: list[tuple[str, list[str]]] = []
    for item in items:
        key, sep, raw = item.partition("=")
        values = [v.strip() for v in raw.split(",")]
        if not sep or not key.strip():
            raise ValueError(f"--vary {item!r}: expected dotted.path=V1,V2,...")
        if not all(values):
            raise ValueError(f"--vary {item!r}: an empty value in {raw!r}")
        if len(set(values)) != len(values):
            raise ValueError(f"--vary {item!r}: a value given twice")
        if any(key.strip() == k for k, _ in out):
            raise ValueError(f"--vary {key.strip()!r} given twice; list all its values in one")
        out.append((key.strip(), values))
    if not out:
        raise ValueError("sweep needs at least one --vary KEY=V1,V2,...")
    return out


def points(base: MissionProfile, ask: SweepAsk) -> list[Point]:
    """Every point's validated profile: --set, then --method, then the point's values, each
    refused (ProfileError/ValueError naming the field and value) before any run."""
    profile = apply_overrides(base, ask.overrides)
    if ask.method:
        profile = with_method(profile, ask.method)
    keys = [k for k, _ in ask.vary]
    out = []
    for i, values in enumerate(itertools.product(*(v for _, v in ask.vary))):
        settings = [f"{k}={v}" for k, v in zip(keys, values, strict=True)]
        try:
            point = apply_overrides(profile, settings)
        except ProfileError as exc:
            raise ProfileError(f"--vary point {', '.join(settings)}: {exc}") from None
        out.append(Point(i, values, point))
    return out


def config_columns(ask: SweepAsk, point: Point) -> dict[str, str | int | float]:
    """The samples' configuration columns of a point: its label, index and each value."""
    pairs = [(k, v) for (k, _), v in zip(ask.vary, point.values, strict=True)]
    return {
        "config": " ".join(f"{k}={v}" for k, v in pairs),
        "point": point.index,
        **dict(pairs),
    }


def open_folder(folder: Path, ask: SweepAsk) -> None:
    """Create the sweep folder, or check that it holds the same ask (then it resumes)."""
    path = folder / ASK_FILE
    mine = json.loads(json.dumps(ask.as_dict()))
    if path.exists():
        theirs = json.loads(path.read_text(encoding="utf-8"))
        if theirs != mine:
            raise ValueError(
                f"--out {folder}: holds another sweep ({ASK_FILE}: {json.dumps(theirs)}); "
                "give another --out, or delete the folder to start again"
            )
        return
    (folder / POINTS).mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(mine, indent=2) + "\n", encoding="utf-8")


def _point_file(folder: Path, index: int, stem: str) -> Path:
    return folder / POINTS / f"{index:04d}-{stem}.parquet"


def done(folder: Path, index: int) -> bool:
    """A point is done once its runs file is there (written last, by rename)."""
    return _point_file(folder, index, RUNS).is_file()


def _save(folder: Path, ask: SweepAsk, point: Point, res: MissionResults) -> None:
    """The point's samples, each file written beside and renamed into place: a sweep killed
    while writing leaves no half file, and the point is done only once both are in."""
    import pyarrow.parquet as pq

    tables = sample_tables([(config_columns(ask, point), res)])
    for stem in (CONFIRMATIONS, RUNS):
        final = _point_file(folder, point.index, stem)
        part = final.with_suffix(".part")
        pq.write_table(tables[stem], part)
        os.replace(part, final)


def run_points(
    folder: Path,
    ask: SweepAsk,
    todo: list[Point],
    *,
    workers: int,
    scheduler: str | None,
    progress: Callable[[int], None],
    interrupted: Callable[[], bool] = lambda: False,
) -> None:
    """Simulate the points not yet done, ``workers`` at a time (each point is one block of
    runs per 1000; a batch keeps every worker busy), saving each batch as it finishes.
    Ctrl-C saves the points of the batch that had finished and raises KeyboardInterrupt.

    ``interrupted``: whether a Ctrl-C came, checked between batches. Its KeyboardInterrupt
    can be lost: raised in a fork handler (the next batch's workers start), Python prints it
    as "Exception ignored" and goes on; a worker forked that moment dies of it."""
    batch = max(workers, 1)
    for start in range(0, len(todo), batch):
        if interrupted():
            raise KeyboardInterrupt
        group = todo[start : start + batch]
        try:
            results = run_many(
                [p.profile for p in group],
                runs=ask.runs,
                seed=ask.seed,
                workers=workers,
                scheduler=scheduler,
                progress=progress,
            )
        except RunInterruptedError as stop:
            for i, res in stop.finished.items():
                _save(folder, ask, group[i], res)
            raise KeyboardInterrupt from None
        except RuntimeError:
            if interrupted():  # a worker killed by the Ctrl-C as it started
                raise KeyboardInterrupt from None
            raise
        for point, res in zip(group, results, strict=True):
            _save(folder, ask, point, res)
    if interrupted():
        raise KeyboardInterrupt


def combined(folder: Path, all_points: list[Point]) -> dict[str, pa.Table]:
    """The samples of every point, in point order, as one runs and one confirmations table."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    return {
        stem: pa.concat_tables(
            [pq.read_table(_point_file(folder, p.index, stem)) for p in all_points],
            promote_options="permissive",
        )
        for stem in (RUNS, CONFIRMATIONS)
    }
