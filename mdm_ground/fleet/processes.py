"""The fleet's child processes: each in its own process group, so a terminal's Ctrl-C (sent to
the foreground process group) reaches only the fleet, which decides what each child gets. On
Linux each child is also sent SIGTERM when the fleet dies without stopping it (SIGKILL, OOM
killer): the emulator exits and a companion ends its mission as on any SIGTERM, instead of
flying on as an orphan."""

from __future__ import annotations

import ctypes
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from types import FrameType

_PR_SET_PDEATHSIG = 1
_prctl = ctypes.CDLL(None, use_errno=True).prctl if sys.platform == "linux" else None
"""Looked up before any fork: after it, in the child, only the call itself runs."""


def _terminate_with_parent() -> None:
    if _prctl is not None:
        _prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)


def start(
    command: list[str], log: Path, env: dict[str, str], *, append: bool
) -> subprocess.Popen[bytes]:
    """``command`` in a new session (its own process group), output to ``log``; SIGTERM to it
    when the thread that started it ends (Linux: the fleet's main thread, so the fleet)."""
    with log.open("ab" if append else "wb") as f:
        return subprocess.Popen(
            command,
            stdout=f,
            stderr=subprocess.STDOUT,
            env=env,
            start_new_session=True,
            preexec_fn=_terminate_with_parent,  # noqa: PLW1509 - resolved before the fork
        )


def signal_one(p: subprocess.Popen[bytes], sig: signal.Signals) -> None:
    """``sig`` to the process alone (a MAVSDK companion's mavsdk_server must keep serving it
    while it flies its end action)."""
    if p.poll() is None:
        p.send_signal(sig)


def kill_group(p: subprocess.Popen[bytes]) -> None:
    """SIGKILL the process and everything it started."""
    if p.poll() is None:
        with suppress(ProcessLookupError):
            os.killpg(p.pid, signal.SIGKILL)
        p.wait()


def stop(p: subprocess.Popen[bytes], grace: float) -> None:
    """SIGTERM, then SIGKILL to its group after ``grace`` wall seconds."""
    signal_one(p, signal.SIGTERM)
    wait_all([p], grace)
    kill_group(p)


def wait_all(processes: list[subprocess.Popen[bytes]], seconds: float) -> bool:
    """True when every process ended within ``seconds``."""
    deadline = time.monotonic() + seconds
    while any(p.poll() is None for p in processes):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.05)
    return True


class StopRequests:
    """SIGINT/SIGTERM to the fleet, counted: the first asks for a clean stop, a second for an
    immediate one. Only the main thread can take signals; elsewhere the count stays 0."""

    def __init__(self) -> None:
        self.count = 0
        self.signal_name = ""

    def _take(self, signum: int, _frame: FrameType | None) -> None:
        self.count += 1
        self.signal_name = signal.Signals(signum).name

    @contextmanager
    def installed(self) -> Iterator[StopRequests]:
        if threading.current_thread() is not threading.main_thread():
            yield self
            return
        before = {sig: signal.signal(sig, self._take) for sig in (signal.SIGINT, signal.SIGTERM)}
        try:
            yield self
        finally:
            for sig, handler in before.items():
                signal.signal(sig, handler)
