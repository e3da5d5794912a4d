"""--lockstep: sim time waits at each tick for a client streaming setpoints in OFFBOARD, and
stops waiting for a client that went quiet for longer than lockstep_wall (wall s)."""

from __future__ import annotations

import time

import pytest

from tests.emulator_harness import Client, make_config, running_emulator

PX4_OFFBOARD = 0x60000


@pytest.mark.timeout(60)
def test_lockstep_holds_sim_time_for_a_streaming_client_only() -> None:
    cfg = make_config(1, 25350, personas=("px4",), lockstep=True, lockstep_wall=1.0)
    with running_emulator(cfg) as emu, Client(25350, 1) as c:
        assert c.pump(5, lambda m: m.get_type() == "HEARTBEAT") is not None
        c.heartbeat()
        assert c.command(400, 1) == 0
        c.stream(lambda: c.velocity(0, 0, -1.0), 0.3)
        assert c.command(176, 1, 6, 0) == 0
        assert c.stream_until(
            lambda: c.velocity(0, 0, -1.0),
            lambda m: m.get_type() == "HEARTBEAT" and m.custom_mode == PX4_OFFBOARD,
            5.0,
        )
        c.stream(lambda: c.velocity(0, 0, -1.0), 0.5)
        held = emu.clock.now
        c.pump(0.6)  # quiet for less than lockstep_wall: the clock waits for the setpoint
        assert emu.clock.now - held <= 0.25
        assert emu.lockstep_waits > 0
        time.sleep(1.0)  # the silence under test, with the next line's 1 s
        c.pump(1.0)  # quiet for longer: not waited for any more (10x: ~10 sim s per wall s)
        assert emu.clock.now - held > 3.0
