"""Which commit a benchmark measured: a run of an older commit (a worktree on PYTHONPATH) says
so in its output."""

from __future__ import annotations

import subprocess
from pathlib import Path


def commit_of(where: Path | str, form: str = "%h") -> str:
    """``git log -1 --format=form`` of the checkout at ``where``; 'unknown (where)' outside one."""
    done = subprocess.run(
        ["git", "-C", str(where), "log", "-1", f"--format={form}"],
        capture_output=True,
        text=True,
        check=False,
    )
    return done.stdout.strip() or f"unknown ({where})"
