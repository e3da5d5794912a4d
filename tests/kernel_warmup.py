"""numba's disk cache filled once before pytest-xdist's workers start.

On a fresh clone no kernel is cached yet, and each worker compiles the kernels it first calls,
all at once: the Monte-Carlo engines alone took 48 s of CPU to compile in one process (22 s the
MDM engine, 23 s the swarms, 3 s the lawnmowers) against 1 s loaded from the cache, so three
workers compiling the same kernels side by side cost about 100 s of CPU that the two cores
would otherwise give to the tests. The controller compiles them here instead, in one process per
part, side by side (``python -m tests.kernel_warmup PART``), and the workers and every emulator
or engine started as a process load them from the cache. With the cache already filled the
parts only load it (about 2 s each).

A part that fails says so and the session goes on: the tests that use that kernel then report
what is wrong.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PARTS = ("engines", "swarms", "emulator")


def warm() -> None:
    """Run every part in its own process, side by side; a failure (or a part still running
    after 600 s, then ended) is printed, not raised."""
    procs = {
        part: subprocess.Popen(
            [sys.executable, "-m", "tests.kernel_warmup", part],
            cwd=ROOT,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        for part in PARTS
    }
    for part, proc in procs.items():
        try:
            out, _ = proc.communicate(timeout=600)
        except subprocess.TimeoutExpired:
            proc.kill()
            out, _ = proc.communicate()
        if proc.returncode != 0:
            print(f"\nkernel warm-up {part!r} failed ({proc.returncode}):\n{out[-2000:]}")


def _run_engines(methods: list[tuple[str, str]]) -> None:
    from mdm_montecarlo.engines.runner import run_many
    from mdm_montecarlo.study.variants import with_method
    from mdm_profiles import builtin_profile

    profiles = [with_method(builtin_profile(name), method) for name, method in methods]
    run_many(profiles, runs=2, seed=1, workers=1)


def _run_emulator() -> None:
    """One emulated vehicle for a vehicle second: its step, tilt, read-out and WGS84 kernels."""
    from tests.emulator_harness import free_udp_base

    with tempfile.TemporaryDirectory() as folder:
        events = Path(folder) / "events.jsonl"
        base = free_udp_base(1, gap=100)
        subprocess.run(
            [sys.executable, "-m", "sim_vehicle_stub.cli", "--profile", "paper-fixed",
             "-n", "1", "--base-port", str(base), "--bind-port-base", str(base + 100),
             "--speedup", "10", "--duration", "1", "--events", str(events)],
            check=True, capture_output=True, timeout=300,
        )  # fmt: skip


def main(part: str) -> None:
    scenarios = ("paper-fixed", "paper-dynamic", "paper-popup")
    if part == "engines":
        singles = [(s, m) for s in scenarios for m in ("MDM:LS+BS", "US", "LM1", "LM2")]
        _run_engines(singles)
    elif part == "swarms":
        _run_engines([(s, m) for s in scenarios for m in ("PSO", "SPSO", "ARPSO")])
    elif part == "emulator":
        _run_emulator()
    else:
        raise SystemExit(f"unknown part {part!r}; parts: {', '.join(PARTS)}")


if __name__ == "__main__":
    main(sys.argv[1])
