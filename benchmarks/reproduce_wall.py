"""Wall and CPU time of the full `mdm-montecarlo reproduce` (every table of section IV).

    .venv/bin/python benchmarks/reproduce_wall.py                 # 1000 runs per row, all cores
    .venv/bin/python benchmarks/reproduce_wall.py --runs 200 --tables simtable1,simtablepso1

It runs the real command line in a child process and prints the commit, its wall time, the
CPU seconds the child and its workers used, the shares of start-up, simulation and report (as
reproduce reports them) and the load average before and after (this machine is shared: a
wall time taken under load says little; CPU seconds / cores is the floor on an idle machine).
Set PYTHONPATH to another commit's worktree to time that commit with the same script.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from code_commit import commit_of


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--tables", help="comma-separated subset (default: all)")
    parser.add_argument(
        "--workers", type=int, help="worker processes (default: reproduce's, all cores)"
    )
    args = parser.parse_args()
    exe = Path(sys.executable).with_name("mdm-montecarlo")
    with tempfile.TemporaryDirectory() as out:
        cmd = [str(exe), "reproduce", "--runs", str(args.runs), "--out", out, "--no-progress"]
        if args.workers is not None:
            cmd += ["--workers", str(args.workers)]
        if args.tables:
            cmd += ["--tables", args.tables]
        load_before = os.getloadavg()[0]
        start = time.perf_counter()
        done = subprocess.run(cmd, capture_output=True, text=True, check=False)
        wall = time.perf_counter() - start
        load_after = os.getloadavg()[0]
        if done.returncode != 0:
            print(done.stderr, file=sys.stderr)
            return done.returncode
        header = (Path(out) / "report.md").read_text().splitlines()[2]
    phases = [line for line in done.stderr.splitlines() if line.startswith("phases:")]
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = usage.ru_utime + usage.ru_stime
    cores = os.cpu_count() or 1
    print(f"commit       {_commit()}")
    print(f"command      reproduce --runs {args.runs} --tables {args.tables or 'all'}")
    print(f"report       {header}")
    print(f"wall         {wall:.1f} s")
    print(f"cpu          {cpu:.1f} s over {cores} cores (idle-machine floor {cpu / cores:.1f} s)")
    print(f"shares       {phases[0].removeprefix('phases: ') if phases else 'not reported'}")
    print(f"load average {load_before:.1f} before, {load_after:.1f} after")
    return 0


def _commit() -> str:
    """The commit of the code that ran: PYTHONPATH's worktree if set, else this one's."""
    where = os.environ.get("PYTHONPATH", "").split(os.pathsep)[0] or str(Path(__file__).parent)
    return commit_of(where, "%h %s")[:72]


if __name__ == "__main__":
    raise SystemExit(main())
