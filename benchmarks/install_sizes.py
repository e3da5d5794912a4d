"""The two installs of issue 45 and `companion run`'s memory: the package's wheel installed into a
fresh virtual environment alone (the vehicle side) and with `[all]` (every command), each
environment's size on disk and package count, then one 60-vehicle-s emulated search flown by
each environment's `companion run` against the emulator of the project's environment, with the
companion's peak resident memory (VmHWM).

Usage: python benchmarks/install_sizes.py [WORK_DIR]   (default: a temporary folder)
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tests.vehicle_venv import build_wheel, fly, make_venv, size_mb


def _packages(venv: Path) -> int:
    listed = subprocess.run(
        [str(venv / "bin" / "pip"), "list", "--format=freeze"],
        capture_output=True, text=True, check=True, timeout=120,
    ).stdout  # fmt: skip
    return len(listed.splitlines())


def main() -> None:
    work = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="mdm-inst-"))
    wheel = build_wheel(work / "wheel")
    print(f"wheel {wheel.name}: {wheel.stat().st_size / 1e6:.2f} MB")
    for name, extra in (("vehicle (default)", ""), ("all ([all])", "all")):
        venv = make_venv(work / (extra or "vehicle"), wheel, extra)
        flight = fly(venv, work / f"run-{extra or 'vehicle'}")
        seen = flight.vehicle
        print(
            f"{name:18} {size_mb(venv):7.0f} MB, {_packages(venv):3} packages; companion run: "
            f"exit {flight.returncode}, flew {seen.distance:.0f} m, "
            f"{'landed' if seen.alt < 1.0 and not seen.armed else 'NOT landed'}, "
            f"peak RSS {flight.max_rss_mb:.0f} MB",
            flush=True,
        )


if __name__ == "__main__":
    main()
