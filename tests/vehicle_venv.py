"""A fresh virtual environment holding the package as a field engineer installs it on a vehicle
(from a local wheel, with its extras or none: the vehicle side alone), and one emulated flight
of `companion run` from it against the emulator started from the project's own environment.

Used by tests/companion/test_vehicle_install.py and benchmarks/install_sizes.py."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from tests.companion.sitl_observer import Observer, Trace
from tests.emulator_harness import free_udp_base

ROOT = Path(__file__).resolve().parents[1]
BIND_OFFSET = 100
"""The emulator binds vehicle i's own port at base + BIND_OFFSET + i."""


def build_wheel(folder: Path) -> Path:
    """The package's wheel, built from the repository into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(folder), str(ROOT)],
        check=True,
        capture_output=True,
        timeout=300,
    )
    (wheel,) = folder.glob("mdm_search-*.whl")
    return wheel


def make_venv(folder: Path, wheel: Path, extras: str = "") -> Path:
    """A new virtual environment in ``folder`` with ``wheel`` installed (``extras``: e.g.
    ``"all"``; none: the vehicle side alone), its dependencies from the package index."""
    subprocess.run([sys.executable, "-m", "venv", str(folder)], check=True, timeout=120)
    target = f"mdm-search[{extras}] @ {wheel.as_uri()}" if extras else str(wheel)
    done = subprocess.run(
        [str(folder / "bin" / "pip"), "install", "-q", target],
        capture_output=True,
        text=True,
        timeout=900,
        check=False,
    )
    if done.returncode != 0:
        raise AssertionError(f"pip install {target} failed:\n{done.stdout}\n{done.stderr}")
    return folder


def size_mb(folder: Path) -> float:
    """Bytes on disk below ``folder`` (each file once), in MB."""
    total = 0
    for path in folder.rglob("*"):
        if path.is_file() and not path.is_symlink():
            total += path.stat().st_blocks * 512
    return total / 1e6


@dataclass(frozen=True)
class Flight:
    """One `companion run` against the emulator, as it ended."""

    returncode: int
    max_rss_mb: float
    out: Path
    vehicle: Trace
    """What the vehicle did, seen on its own second link (the emulator's vehicle port)."""


def emulator(out: Path, base: int, *, speedup: float = 10.0) -> subprocess.Popen[bytes]:
    """One emulated PX4 vehicle of paper-fixed, from the project's environment, sending to
    ``base`` (the companion's port) and writing its ground truth to emulator-events.jsonl."""
    with (out / "emulator.log").open("ab") as log:
        return subprocess.Popen(
            [sys.executable, "-m", "sim_vehicle_stub.cli", "--profile", "paper-fixed",
             "-n", "1", "--base-port", str(base), "--bind-port-base", str(base + BIND_OFFSET),
             "--speedup", str(speedup), "--seed", "3",
             "--events", str(out / "emulator-events.jsonl")],
            stdout=log, stderr=subprocess.STDOUT,
            env=dict(os.environ, PYTHONUNBUFFERED="1"),
        )  # fmt: skip


def _peak_rss_kb(pid: int) -> int:
    """The process's peak resident memory so far (VmHWM), kB; 0 once it has gone. Read from
    /proc rather than from its rusage, which counts the test process's memory at the fork."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return 0
    for line in status.splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1])
    return 0


def fly(
    venv: Path,
    out: Path,
    *,
    duration: float = 60.0,
    speedup: float = 10.0,
    base: int | None = None,
    link: tuple[str, ...] = (),
    during: Callable[[subprocess.Popen[bytes]], None] = lambda _: None,
    draw_map: bool = True,
) -> Flight:
    """`companion run` of ``venv`` flying vehicle 0 for ``duration`` vehicle s against an
    emulator of its own sending to ``base`` (default: a free port, the companion's), to the
    landing; its exit status and peak resident memory. ``link``: the companion's link options
    (default: its own UDP port ``base``); ``during`` runs once the companion has started;
    ``draw_map``: False for `--no-map`."""
    out.mkdir(parents=True, exist_ok=True)
    base = free_udp_base(1, gap=BIND_OFFSET) if base is None else base
    emu = emulator(out, base, speedup=speedup)
    observer = Observer(f"udpout:127.0.0.1:{base + BIND_OFFSET}", sysid=1)
    try:
        with (out / "companion-0.log").open("ab") as log:
            companion = subprocess.Popen(
                [str(venv / "bin" / "companion"), "run", "--profile", "paper-fixed",
                 "--vehicle", "0", *(link or ("--base-port", str(base))),
                 *(() if draw_map else ("--no-map",)),
                 "--duration", str(duration), "--land-wait", "600",
                 "--max-speedup", str(speedup), "--seed", "5",
                 "--log-dir", str(out)],
                stdout=log, stderr=subprocess.STDOUT, cwd=out,
            )  # fmt: skip
        try:
            during(companion)
            peak_kb = 0
            while companion.poll() is None:
                peak_kb = max(peak_kb, _peak_rss_kb(companion.pid))
                time.sleep(0.25)
        finally:
            if companion.poll() is None:
                companion.kill()
                companion.wait()
        seen = observer.snapshot()
    finally:
        observer.close()
        emu.terminate()
        emu.wait(timeout=20)
    return Flight(companion.returncode, peak_kb / 1024.0, out, seen)
