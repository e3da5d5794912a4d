"""--lockstep: sim time waits at each tick for a client streaming setpoints in OFFBOARD, and
stops waiting for a client that left a held tick unanswered for lockstep_wall (wall s), and
only for that client."""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from tests.emulator_harness import Client, emulator_and_loop, make_config, running_emulator

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


def _ack_or_position(m: Any) -> bool:
    return Client._ack_for_us(m, 176) or m.get_type() == "LOCAL_POSITION_NED"


class _Answerer(threading.Thread):
    """A client on its own thread: into OFFBOARD, then one setpoint (and a heartbeat) per
    position received, as a companion does, until ``quiet`` is set; the positions answered are
    in ``client.log``."""

    def __init__(self, port: int, sysid: int, delay: float = 0.0) -> None:
        super().__init__(daemon=True)
        self.delay = delay
        """Wall s between a position and its answer."""
        self.client = Client(port, sysid)
        self.offboard = threading.Event()
        self.quiet = threading.Event()
        self.done = threading.Event()
        self.at_quiet: Callable[[Client], object] | None = None
        """Called at the first position left unanswered once ``quiet`` is set."""

    def run(self) -> None:
        c = self.client
        try:
            assert c.pump(5, lambda m: m.get_type() == "HEARTBEAT") is not None
            c.heartbeat()
            assert c.command(400, 1) == 0
            # Flat out, a setpoint ages a sim second in a few wall ms: send it with the command.
            c.velocity(0, 0, -1.0)
            c.conn.mav.command_long_send(c.sysid, 1, 176, 0, 1, 6, 0, 0, 0, 0, 0)
            ack = c.pump(2.0, _ack_or_position)
            while ack is not None and ack.get_type() != "COMMAND_ACK":
                c.heartbeat()
                c.velocity(0, 0, -1.0)
                ack = c.pump(2.0, _ack_or_position)
            assert ack is not None
            assert ack.result == 0
            self.offboard.set()
            c.log.clear()
            while True:
                if c.pump(0.05, lambda m: m.get_type() == "LOCAL_POSITION_NED") is not None:
                    if self.quiet.is_set():
                        if self.at_quiet is not None:
                            self.at_quiet(c)
                        break
                    time.sleep(self.delay)
                    c.heartbeat()
                    c.velocity(0, 0, -1.0)
        finally:
            self.done.set()


@pytest.mark.timeout(60)
def test_a_late_emulator_still_waits_for_the_clients_that_answered(tmp_path: Path) -> None:
    """Two clients answer every tick, flat out, client 1 20 wall ms after each position. Client
    2 goes quiet in OFFBOARD (a companion that ended, or is starved), and 0.1 wall s into the
    tick held for it the emulator's own loop is held off the CPU for 0.35 wall s (a busy host).
    The hold times out; from then on only vehicle 2 is not waited for (its failsafe acts):
    client 1, which answered the held tick, gets every tick and its vehicle stays in OFFBOARD.
    (Before, lockstep judged a client silent by the wall time since its last setpoint: after
    the late time-out client 1's answer looked stale too, sim time ran on for the 20 ms
    client 1 took to answer, and vehicle 1 fell back on the setpoint-loss failsafe.)"""
    events = tmp_path / "events.jsonl"
    cfg = make_config(2, 25360, personas=("px4", "px4"), speedup=None, lockstep=True, events=events)
    with emulator_and_loop(cfg) as (emu, loop):
        a, b = _Answerer(25360, 1, delay=0.02), _Answerer(25361, 2)
        a.start()
        b.start()
        assert a.offboard.wait(15)
        assert b.offboard.wait(15)
        time.sleep(0.5)
        assert a.client.log, "client 1 answers ticks"
        assert b.client.log, "client 2 answers ticks"
        # Client 2 leaves a tick unanswered; 0.1 wall s into the tick's hold, when client 1
        # has long answered it, the emulator's loop is held off the CPU for 0.35 wall s.
        b.at_quiet = lambda _: loop.call_soon_threadsafe(loop.call_later, 0.1, time.sleep, 0.35)
        b.quiet.set()
        assert b.done.wait(5)
        time.sleep(1.5)
        a_quiet = emu.clock.now  # client 1 goes quiet too: its vehicle's hold times out
        a.quiet.set()
        assert a.done.wait(5)
        b.client.pump(0.5)
        assert a.client.mode() == PX4_OFFBOARD
        assert b.client.mode() != PX4_OFFBOARD  # vehicle 2 was not waited for: failsafe
        a.client.close()
        b.client.close()
    silent = [
        e
        for e in map(json.loads, events.read_text().splitlines())
        if e["event"] == "lockstep_silent"
    ]
    assert [e["vehicle"] for e in silent if e["t"] < a_quiet] == [1]


@pytest.mark.timeout(60)
def test_a_vehicle_switched_out_of_offboard_is_not_waited_for() -> None:
    """Client 2 answers a tick by switching its vehicle to POSCTL instead of sending a setpoint
    (a companion ending its search): the held tick goes on as soon as the others answered, not
    after ``lockstep_wall`` (here 30 wall s)."""
    cfg = make_config(
        2, 25370, personas=("px4", "px4"), speedup=None, lockstep=True, lockstep_wall=30.0
    )
    with running_emulator(cfg) as emu:
        a, b = _Answerer(25370, 1), _Answerer(25371, 2)
        a.start()
        b.start()
        assert a.offboard.wait(15)
        assert b.offboard.wait(15)
        time.sleep(0.5)  # both answer ticks in OFFBOARD
        b.at_quiet = lambda c: c.conn.mav.command_long_send(2, 1, 176, 0, 1, 3, 0, 0, 0, 0, 0)
        b.quiet.set()
        assert b.done.wait(5)
        a.client.log.clear()
        time.sleep(1.5)
        a.quiet.set()
        assert a.done.wait(5)
        assert len(a.client.log) > 100, "sim time stood still: the tick waited for vehicle 2"
        assert emu.lockstep_waits > 100
        b.client.pump(0.5)
        assert b.client.mode() == 0x30000  # POSCTL, by the command
        a.client.close()
        b.client.close()
