"""What writing the per-run samples and the provenance adds to `reproduce`: the wall and CPU
time of ``write_result_files`` (samples-runs and samples-confirmations as Parquet and CSV,
provenance.json) for the rows of some tables, and the files' sizes.

    .venv/bin/python benchmarks/samples_write.py                        # simtable1, 1000 runs
    .venv/bin/python benchmarks/samples_write.py --tables simtable1,simtablepso1,scaling

The simulation runs first (not timed); the load average is printed beside the figures, as this
machine is shared.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from mdm_montecarlo.commands.result_files import case_columns, write_result_files
from mdm_montecarlo.engines.runner import run_many
from mdm_montecarlo.study.cases import study_rows
from mdm_provenance import collect


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tables", default="simtable1")
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    args = parser.parse_args()
    cases = list(dict.fromkeys(r.case for r in study_rows(tuple(args.tables.split(",")))))
    results = run_many(
        [c.profile() for c in cases], runs=args.runs, seed=2024, workers=args.workers
    )
    configs = [(case_columns(c), res) for c, res in zip(cases, results, strict=True)]
    with tempfile.TemporaryDirectory() as out:
        load = os.getloadavg()[0]
        wall, cpu = time.perf_counter(), time.process_time()
        record = collect(seed=2024, started=wall)
        write_result_files(Path(out), configs, record)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        sizes = {p.name: p.stat().st_size for p in sorted(Path(out).iterdir())}
    print(f"commit       {record.git_commit}{' (dirty tree)' if record.git_dirty else ''}")
    print(f"rows         {len(cases)} configurations x {args.runs} runs ({args.tables})")
    print(f"write        {wall:.2f} s wall, {cpu:.2f} CPU-s (load {load:.1f} before)")
    for name, size in sizes.items():
        print(f"  {name:32s} {size / 1e6:8.2f} MB")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
