"""Wall time of `mdm-montecarlo plan`: 6 team sizes x 4 methods x 1000 runs (target ~10 s),
run as a child process as a user runs it, beside `reproduce --tables simtable1` measured the
same way (benchmarks/README.md, "The planner's time").

    .venv/bin/python benchmarks/plan_speed.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BIN = Path(sys.executable).parent / "mdm-montecarlo"
PLAN = [
    "plan",
    "--profile",
    "field-duebendorf",
    "--teams",
    "1,2,3,4,6,8",
    "--endurance",
    "15",
    "--methods",
    "MDM,US,LM1,LM2",
    "--runs",
    "1000",
    "--workers",
    "2",
]
REPRODUCE = [
    "reproduce",
    "--tables",
    "simtable1",
    "--runs",
    "1000",
    "--workers",
    "2",
    "--no-progress",
]


def _wall(args: list[str]) -> float:
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        subprocess.run([str(BIN), *args, "--out", out], check=True, capture_output=True)
        return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    _wall(PLAN)  # the kernels compiled and cached before timing
    for name, command in (("plan 6 x 4 x 1000", PLAN), ("reproduce simtable1", REPRODUCE)):
        times = [_wall(command) for _ in range(args.repeat)]
        print(f"{name}: wall {min(times):.1f} s best, {max(times):.1f} s worst of {args.repeat}")


if __name__ == "__main__":
    main()
