"""The provenance record and how each of its fields is found on this machine."""

from __future__ import annotations

import platform
import resource
import subprocess
import sys
import time
from dataclasses import asdict, dataclass
from importlib import metadata
from pathlib import Path

DISTRIBUTION = "mdm-search"
_CHECKOUT = Path(__file__).resolve().parents[1]
_VECTOR_PREFIXES = ("sse", "ssse", "avx", "fma", "f16c", "amx", "asimd", "neon", "sve")
"""CPU flags that name vector instruction sets (x86 SSE/AVX/FMA/AMX, Arm NEON/ASIMD/SVE)."""


@dataclass(frozen=True)
class Provenance:
    """Everything a reader needs to tell whether two results came from the same code and
    machine, and how to run it again."""

    package_version: str
    git_commit: str | None
    """HEAD of the checkout the code was imported from; None outside a git checkout."""
    git_dirty: bool | None
    """Whether tracked files differed from that commit; None outside a git checkout."""
    python: str
    numpy: str | None
    numba: str | None
    cpu_model: str
    cpu_vector_flags: list[str]
    seed: int | None
    command_line: list[str]
    wall_s: float
    cpu_s: float
    """User + system CPU of this process and of its finished children (the workers)."""

    def as_dict(self) -> dict[str, object]:
        return asdict(self)


def package_version() -> str:
    """The installed version of mdm-search (pyproject.toml's), or 'unknown' when the
    package runs from a tree that was never installed."""
    try:
        return metadata.version(DISTRIBUTION)
    except metadata.PackageNotFoundError:
        return "unknown"


def version_text(prog: str) -> str:
    """What ``PROG --version`` prints: the program, the version and the commit if known."""
    commit, dirty = _git_state()
    where = "" if commit is None else f" (git {commit[:12]}{', dirty tree' if dirty else ''})"
    return f"{prog} {package_version()}{where}"


def cpu_seconds() -> float:
    """User + system CPU of this process and of its finished children (workers, plotters)."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def collect(
    *,
    seed: int | None,
    started: float,
    cpu_started: float = 0.0,
    command_line: list[str] | None = None,
) -> Provenance:
    """The record for a result finished now; ``started`` is the ``time.perf_counter()`` at
    which the command began, ``cpu_started`` the :func:`cpu_seconds` then, ``command_line``
    the command as given (default: this process's ``sys.argv``)."""
    commit, dirty = _git_state()
    model, flags = _cpu()
    return Provenance(
        package_version=package_version(),
        git_commit=commit,
        git_dirty=dirty,
        python=platform.python_version(),
        numpy=_version_of("numpy"),
        numba=_version_of("numba"),
        cpu_model=model,
        cpu_vector_flags=flags,
        seed=seed,
        command_line=list(sys.argv if command_line is None else command_line),
        wall_s=round(time.perf_counter() - started, 3),
        cpu_s=round(cpu_seconds() - cpu_started, 3),
    )


def _version_of(distribution: str) -> str | None:
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return None


def _git(*args: str) -> str | None:
    try:
        done = subprocess.run(
            ["git", "-C", str(_CHECKOUT), *args],
            capture_output=True,
            text=True,
            timeout=10,
            check=False,
        )
    except (OSError, subprocess.TimeoutExpired):
        return None
    return done.stdout if done.returncode == 0 else None


def _git_state() -> tuple[str | None, bool | None]:
    """(commit, dirty) of the checkout this package was imported from; (None, None) for an
    installed wheel, where there is no checkout to ask."""
    if not (_CHECKOUT / ".git").exists():
        return None, None
    head = _git("rev-parse", "HEAD")
    if head is None:
        return None, None
    status = _git("status", "--porcelain", "--untracked-files=no")
    return head.strip(), None if status is None else bool(status.strip())


def _cpu() -> tuple[str, list[str]]:
    """The CPU's model name and its vector instruction-set flags, from /proc/cpuinfo where
    there is one (Linux), else what the platform module says (no flags)."""
    model = platform.processor() or platform.machine()
    flags: list[str] = []
    try:
        text = Path("/proc/cpuinfo").read_text(encoding="utf-8", errors="replace")
    except OSError:
        return model, flags
    for line in text.splitlines():
        key, _, value = line.partition(":")
        key = key.strip().lower()
        if key in ("model name", "cpu model", "hardware") and value.strip():
            model = value.strip()
        elif key in ("flags", "features") and not flags:
            flags = sorted(f for f in value.split() if f.startswith(_VECTOR_PREFIXES))
        if key == "" and flags and model:
            break  # the first processor's block is enough
    return model, flags
