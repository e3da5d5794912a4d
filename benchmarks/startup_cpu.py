"""What starting each command costs in CPU, the test tiers' price of every subprocess.

    .venv/bin/python benchmarks/startup_cpu.py [--starts 5]

Printed per start: the median user + system CPU seconds of ``--starts`` starts of each entry
point's ``--help`` (their console scripts, and ``python -m`` as `companion fleet` starts its
emulator), of `companion run` refusing a vehicle the profile does not have (everything a real
run imports, then exit 2 before any socket), and of ``python -c "import MODULE"`` for each
entry point's module. CPU, not wall time: the tiers run on 2 busy cores, where the CPU a start
takes is what the other tests wait for. Run it from the repository root, beside
``host_speed.py``: the figures move with the host.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
from pathlib import Path

_BIN = Path(sys.executable).parent
_PYTHON = str(_BIN / "python")

STARTS: dict[str, list[str]] = {
    "companion --help": [str(_BIN / "companion"), "--help"],
    "companion run --help": [str(_BIN / "companion"), "run", "--help"],
    "companion fleet --help": [str(_BIN / "companion"), "fleet", "--help"],
    "companion run, refused": [
        str(_BIN / "companion"),
        "run",
        "--profile",
        "paper-fixed",
        "--vehicle",
        "99",
    ],
    "sim-vehicle --help": [str(_BIN / "sim-vehicle"), "--help"],
    "python -m sim_vehicle_stub.cli --help": [_PYTHON, "-m", "sim_vehicle_stub.cli", "--help"],
    "mdm-montecarlo --help": [str(_BIN / "mdm-montecarlo"), "--help"],
    "import companion.cli": [_PYTHON, "-c", "import companion.cli"],
    "import sim_vehicle_stub.cli": [_PYTHON, "-c", "import sim_vehicle_stub.cli"],
    "import mdm_montecarlo.entry": [_PYTHON, "-c", "import mdm_montecarlo.entry"],
    "python -c pass": [_PYTHON, "-c", "pass"],
}
"""What is started -> its command line (`python -c pass`: the interpreter's own floor)."""


def cpu_s(command: list[str]) -> float:
    """User + system CPU seconds of one run of ``command`` (its output discarded)."""
    child = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, _, usage = os.wait4(child.pid, 0)
    return usage.ru_utime + usage.ru_stime


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--starts", type=int, default=5, help="starts of each command")
    args = parser.parse_args()
    print(f"median CPU s (user + sys) of {args.starts} starts; load {os.getloadavg()[0]:.2f}")
    for name, command in STARTS.items():
        print(f"{name:40s} {statistics.median(cpu_s(command) for _ in range(args.starts)):.3f}")


if __name__ == "__main__":
    main()
