"""`companion fleet` as a user runs it, for the fleet tests: a small profile and the command in
its own session (so a test can signal its process group as a terminal's Ctrl-C does)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from tests.profile_files import write_profile_with


def small_profile(folder: Path, *, tau: float = 0.33) -> str:
    """A 3-vehicle profile on a 3 km square; a huge ``tau`` keeps the vehicles from climbing."""
    path = folder / f"fleet-test-{tau:g}.yaml"
    return str(write_profile_with(path, "fleet-test", fleet={"vehicles": 3, "tau": tau}))


def fleet_command(*args: str) -> list[str]:
    return [sys.executable, "-m", "companion.cli", "fleet", *args]


def start_fleet(*args: str, output: Path) -> subprocess.Popen[bytes]:
    """`companion fleet ARGS` in a new session, stdout and stderr to ``output``."""
    with output.open("wb") as f:
        return subprocess.Popen(
            fleet_command(*args),
            stdout=f,
            stderr=subprocess.STDOUT,
            start_new_session=True,
            env=dict(os.environ, PYTHONUNBUFFERED="1"),
        )


def run_fleet_cli(*args: str, timeout: float = 120.0) -> subprocess.CompletedProcess[str]:
    """`companion fleet ARGS` to the end; output captured."""
    return subprocess.run(
        fleet_command(*args), capture_output=True, text=True, timeout=timeout, check=False
    )


def processes_naming(text: str) -> dict[int, str]:
    """Live processes whose command line contains ``text`` (left-over children of a run):
    pid -> command line."""
    found = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit() or int(entry.name) == os.getpid():
            continue
        try:
            cmd = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if text in cmd:
            found[int(entry.name)] = cmd.strip()
    return found
