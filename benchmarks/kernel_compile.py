"""CPU seconds numba takes to compile each engine's kernels: the first block of one `reproduce`
row per engine (event-driven MDM, interval swarm, waypoint swarm), each in a fresh process
with an empty kernel cache, against the same block once the cache is written.

    .venv/bin/python benchmarks/kernel_compile.py

The first figure is what the first `reproduce` after an install pays per engine (less the
kernels the engines share); the second is a cached load and one block of 5 runs.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

from code_commit import commit_of

_CHILD = """
import sys, time
from mdm_montecarlo.engines.configuration import configure
from mdm_montecarlo.engines.runner import simulate_block
from mdm_montecarlo.study.cases import study_rows
table, method, iteration = sys.argv[1:]
for row in study_rows((table,)):
    profile = row.case.profile()
    swarm = profile.policy.swarm
    if row.case.method == method and (iteration == "-" or swarm.iteration == iteration):
        break
start = time.process_time()
simulate_block(configure(profile), 1, 0, 5)
print(f"{time.process_time() - start:.1f}")
"""

ENGINES = (
    ("event-driven MDM", ("simtable1", "MDM", "-")),
    ("interval swarm", ("simtablepso1", "PSO", "interval")),
    ("waypoint swarm", ("simtablepso1", "PSO", "waypoint")),
)


def main() -> int:
    print(f"commit       {commit_of(str(Path(__file__).parent), '%h %s')[:72]}")
    for name, row in ENGINES:
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "NUMBA_CACHE_DIR": cache}
            cold, warm = (
                subprocess.run(
                    [sys.executable, "-c", _CHILD, *row],
                    env=env,
                    capture_output=True,
                    text=True,
                    check=True,
                ).stdout.strip()
                for _ in range(2)
            )
        print(f"{name:17s} compile + block {cold} CPU-s, cached {warm} CPU-s")
    print(f"load average {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
