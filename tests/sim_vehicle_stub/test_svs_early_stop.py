"""A stop (SIGTERM, Ctrl-C) that reaches `sim-vehicle` while it starts, before its event loop
handles signals (numba loading the kernels takes about a second), ends it cleanly: the fleet
stops an emulator whose companions failed at once, and that must not read as the emulator
failing (tests/ground/test_fleet_failures.py)."""

from __future__ import annotations

import asyncio
import os
import signal
import time
from pathlib import Path

import pytest

from sim_vehicle_stub.cli import _serve, _stops_noted
from tests.emulator_harness import free_udp_base, make_config


@pytest.mark.timeout(60)
def test_a_stop_during_start_up_ends_the_emulator_cleanly(tmp_path: Path) -> None:
    config = make_config(2, free_udp_base(2))
    before = signal.getsignal(signal.SIGTERM)
    with _stops_noted() as stops:
        os.kill(os.getpid(), signal.SIGTERM)  # noted, not acted on: the process lives on
        assert stops == [signal.SIGTERM]
        start = time.monotonic()
        # with no duration the emulator would run until stopped
        asyncio.run(_serve(config, None, tmp_path / "stats.json", stops))
        took = time.monotonic() - start
    assert took < 30.0, "the emulator ran on after the stop"
    assert (tmp_path / "stats.json").exists(), "it did not end through its normal exit"
    assert signal.getsignal(signal.SIGTERM) == before, "the previous handler was not restored"
