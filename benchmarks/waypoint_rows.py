"""CPU seconds of the 27 waypoint swarm rows of `reproduce` (simtablepso1: PSO, SPSO, ARPSO x
fixed / pop-up / dynamic x the waypoint readings), one process, no pool.

    .venv/bin/python benchmarks/waypoint_rows.py                 # 1000 runs per row, 3 passes
    PYTHONPATH=/tmp/before .venv/bin/python benchmarks/waypoint_rows.py --passes 1

Each pass runs `simulate_block` once per row (block 0 of seed 2024, as `reproduce` does at
1000 runs) and prints its CPU seconds; then the least of them, the load average and a hash of
every row's first-confirmation times (equal hashes: the same results). Set PYTHONPATH to
another commit's worktree to time that commit; run each tree once first, so that its kernels
are compiled into its cache before the passes that count.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import time
from pathlib import Path

from code_commit import commit_of

from mdm_montecarlo.engines.runner import is_swarm, simulate_block
from mdm_montecarlo.study.cases import study_rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--passes", type=int, default=3)
    parser.add_argument("--seed", type=int, default=2024)
    args = parser.parse_args()
    profiles = [row.case.profile() for row in study_rows(("simtablepso1",))]
    rows = [p for p in profiles if is_swarm(p) and p.policy.swarm.iteration == "waypoint"]
    cpus = []
    digest = ""
    for k in range(args.passes):
        hashed = hashlib.sha256()
        start = time.process_time()
        for profile in rows:
            hashed.update(simulate_block(profile, args.seed, 0, args.runs).per_vehicle.tobytes())
        cpus.append(time.process_time() - start)
        digest = hashed.hexdigest()[:12]
        print(f"pass {k}       {cpus[-1]:.2f} CPU-s", flush=True)
    where = os.environ.get("PYTHONPATH", "").split(os.pathsep)[0] or str(Path(__file__).parent)
    print(f"commit       {commit_of(where, '%h %s')[:72]}")
    print(f"rows         {len(rows)} x {args.runs} runs, seed {args.seed}")
    print(f"least        {min(cpus):.2f} CPU-s")
    print(f"load average {os.getloadavg()[0]:.1f}")
    print(f"results      {digest}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
