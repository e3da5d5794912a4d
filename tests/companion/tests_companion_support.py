"""Processes for the companion's end-to-end tests: the real emulator and real companions on
127.0.0.1. Port ranges of this directory: 34540-35999 (emulator binds at base + 100)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

SMALL_PROFILE = """
name: small-test
description: three real targets and a false one in a 3 km square, for fault tests
area: {north: 3000.0, east: 3000.0}
targets:
  - {north: 1500.0, east: 1500.0}
  - {north: 700.0, east: 700.0}
  - {north: 2300.0, east: 2300.0}
  - {north: 600.0, east: 2400.0, false_target: true}
fleet: {vehicles: 2, speed: 20.0, tau: 0.33, altitude: 30.0, altitude_step: 5.0}
sensors:
  - {name: detection, radius: 1000.0}
  - {name: confirmation, radius: 200.0}
policy:
  kind: mdm
  memory_radius: 300.0
  levels:
    - {distribution: LS, step: 600.0}
    - distribution: BS
      step: 1000.0
      index: {gamma: 0.1, index_max: 0.95, index_min: 0.2, kappa: 150.0}
mission: {duration: 600.0, ts_cap: 5000.0}
"""


class Procs:
    """Starts and always stops the processes of one test."""

    def __init__(self, out: Path) -> None:
        self.out = out
        self.procs: list[subprocess.Popen[bytes]] = []

    def _start(self, args: list[str], log: str) -> subprocess.Popen[bytes]:
        with (self.out / log).open("ab") as f:
            p = subprocess.Popen(
                [sys.executable, *args], stdout=f, stderr=subprocess.STDOUT,
                env=dict(os.environ, PYTHONUNBUFFERED="1"),
            )  # fmt: skip
        self.procs.append(p)
        return p

    def emulator(self, profile: str, base_port: int, *, vehicles: int = 1, persona: str = "px4",
                 speedup: float = 20.0, extra: tuple[str, ...] = ()) -> subprocess.Popen[bytes]:  # fmt: skip
        return self._start(
            ["-m", "sim_vehicle_stub.cli", "--profile", profile, "-n", str(vehicles),
             "--persona", persona, "--base-port", str(base_port),
             "--bind-port-base", str(base_port + 100), "--speedup", str(speedup),
             "--seed", "3", "--events", str(self.out / "emulator-events.jsonl"), *extra],
            "emulator.log",
        )  # fmt: skip

    def companion(self, profile: str, vehicle: int, base_port: int, *, backend: str = "pymavlink",
                  duration: float = 600.0, extra: tuple[str, ...] = ()) -> subprocess.Popen[bytes]:  # fmt: skip
        return self._start(
            ["-m", "companion.cli", "run", "--profile", profile, "--vehicle", str(vehicle),
             "--base-port", str(base_port), "--backend", backend, "--log-dir", str(self.out),
             "--duration", str(duration), "--land-wait", "0", "--seed", "5", *extra],
            f"companion-{vehicle}.log",
        )  # fmt: skip

    def stop_all(self) -> None:
        for p in self.procs:
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
        for p in self.procs:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


def records(path: Path) -> list[dict[str, Any]]:
    if not path.exists():
        return []
    out = []
    for line in path.read_text().splitlines():
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return out


def wait_for(check: Callable[[], bool], timeout: float, what: str) -> None:
    """Poll ``check`` until true; fails the test naming ``what`` after ``timeout`` wall s."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if check():
            return
        time.sleep(0.2)
    raise AssertionError(f"timed out after {timeout:.0f} s waiting for {what}")


def has(path: Path, event: str, **fields: Any) -> bool:
    return any(
        r.get("event") == event and all(r.get(k) == v for k, v in fields.items())
        for r in records(path)
    )


@pytest.fixture
def procs(tmp_path: Path) -> Iterator[Procs]:
    p = Procs(tmp_path)
    try:
        yield p
    finally:
        p.stop_all()


@pytest.fixture
def small_profile(tmp_path: Path) -> str:
    path = tmp_path / "small-test.yaml"
    path.write_text(SMALL_PROFILE)
    return str(path)
