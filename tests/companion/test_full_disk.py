"""A full disk under the run directory (a real one: a small tmpfs, filled to the last byte
before the companion starts) is a clear error in the log, never a crash: the companion
searches, flies its end action and lands, with the mission log, the .tlog and the log file
each saying once that they could not be written."""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.companion.sitl_observer import Observer
from tests.emulator_harness import free_udp_base
from tests.vehicle_venv import BIND_OFFSET, emulator

VENV = Path(sys.executable).parents[1]


@pytest.fixture
def full_disk(tmp_path: Path) -> Iterator[Path]:
    """A 1 MB tmpfs mounted for the test, filled until a write is refused (ENOSPC)."""
    mount = tmp_path / "disk"
    mount.mkdir()
    if os.geteuid() != 0:
        pytest.skip("mounting a small filesystem to fill needs root")
    done = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(mount)],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.strip()}")
    try:
        with (mount / "filler").open("wb", buffering=0) as filler, contextlib.suppress(OSError):
            while True:
                filler.write(b"\0" * 512)
        yield mount
    finally:
        subprocess.run(["umount", "-l", str(mount)], check=False)


def test_a_full_disk_is_an_error_in_the_log_and_the_vehicle_lands(
    full_disk: Path, tmp_path: Path
) -> None:
    base = free_udp_base(1, gap=BIND_OFFSET)
    run = full_disk / "run"
    emu = emulator(tmp_path, base, speedup=10.0)
    observer = Observer(f"udpout:127.0.0.1:{base + BIND_OFFSET}", sysid=1)
    try:
        done = subprocess.run(
            [str(VENV / "bin" / "companion"), "run", "--profile", "paper-fixed", "--vehicle", "0",
             "--base-port", str(base), "--duration", "40", "--max-speedup", "10", "--no-map",
             "--log-dir", str(run), "--log-file", str(run / "companion.log")],
            capture_output=True, text=True, timeout=400, check=False,
        )  # fmt: skip
        seen = observer.snapshot()
    finally:
        observer.close()
        emu.terminate()
        emu.wait(timeout=20)
    err = done.stderr
    assert done.returncode == 0, done.stdout[-2000:] + err[-3000:]
    assert "Traceback" not in err
    assert "--- Logging error ---" not in err
    assert f"log file {run / 'companion.log'}: [Errno 28] No space left on device" in err, err[
        -3000:
    ]
    assert err.count(f"log file {run / 'companion.log'}: [Errno 28]") == 1  # said once
    assert "No space left on device; records are lost" in err  # the mission log
    assert "No space left on device; no more of the flight is written" in err  # the .tlog
    assert seen.armed_ever
    assert seen.distance > 100.0, f"flew {seen.distance:.0f} m"
    assert not seen.armed
    assert seen.alt < 1.0
    print(f"full disk: flew {seen.distance:.0f} m, landed; "
          f"{sum('No space left' in line for line in err.splitlines())} error line(s)")  # fmt: skip
