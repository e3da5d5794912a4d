"""Test harness: an in-process emulator on its own event-loop thread, and a pymavlink client."""

from __future__ import annotations

import asyncio
import math
import os
import socket
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

from mdm_profiles import builtin_profile
from sim_vehicle_stub.config import EmulatorConfig
from sim_vehicle_stub.emulator import Emulator

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil

__all__ = [
    "PROFILE",
    "TAU",
    "Client",
    "fitted_tau",
    "free_udp_base",
    "make_config",
    "mavutil",
    "running_emulator",
    "step_samples",
]

PROFILE = builtin_profile("paper-fixed")
TAU = PROFILE.fleet.tau


def make_config(n: int, base_port: int, **overrides: Any) -> EmulatorConfig:
    """Vehicles well inside the area (no fence trips), free local ports, 10x speed."""
    start = tuple((1000.0 + 300.0 * i, 1000.0) for i in range(n))
    fields: dict[str, Any] = {
        "profile": PROFILE,
        "vehicles": n,
        "base_port": base_port,
        "bind_port_base": 0,
        "speedup": 10.0,
        "start_positions": start,
    }
    fields.update(overrides)
    return EmulatorConfig(**fields)


@contextmanager
def running_emulator(config: EmulatorConfig) -> Iterator[Emulator]:
    """Run an emulator on a background thread's event loop for the duration of the block."""
    with emulator_and_loop(config) as (emu, _):
        yield emu


@contextmanager
def emulator_and_loop(
    config: EmulatorConfig,
) -> Iterator[tuple[Emulator, asyncio.AbstractEventLoop]]:
    """:func:`running_emulator`, with the event loop it runs on (for a test that schedules
    something on the emulator's own thread)."""
    loop = asyncio.new_event_loop()
    ready = threading.Event()
    holder: dict[str, Emulator] = {}

    def target() -> None:
        asyncio.set_event_loop(loop)

        async def boot() -> None:
            emu = Emulator(config)
            await emu.start()
            holder["emu"] = emu
            ready.set()

        loop.run_until_complete(boot())
        loop.run_forever()

    thread = threading.Thread(target=target, daemon=True)
    thread.start()
    assert ready.wait(10), "emulator did not start"
    emu = holder["emu"]
    try:
        yield emu, loop
    finally:
        asyncio.run_coroutine_threadsafe(emu.stop(), loop).result(10)
        loop.call_soon_threadsafe(loop.stop)
        thread.join(10)
        loop.close()


class Client:
    """A pymavlink ground station bound to the port a vehicle sends first to."""

    def __init__(self, port: int, sysid: int) -> None:
        self.conn: Any = mavutil.mavlink_connection(
            f"udpin:127.0.0.1:{port}", source_system=245, source_component=190
        )
        self.sysid = sysid
        self.last: dict[str, Any] = {}
        self.log: list[Any] = []
        """Every LOCAL_POSITION_NED received, oldest first."""

    def close(self) -> None:
        self.conn.close()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def pump(self, seconds: float, until: Callable[[Any], bool] | None = None) -> Any:
        """Read for up to ``seconds`` (wall); return the first message matching ``until``."""
        deadline = time.monotonic() + seconds
        while (left := deadline - time.monotonic()) > 0:
            msg = self.conn.recv_match(blocking=True, timeout=min(left, 0.05))
            if msg is None or msg.get_srcSystem() != self.sysid:
                continue
            self.last[msg.get_type()] = msg
            if msg.get_type() == "LOCAL_POSITION_NED":
                self.log.append(msg)
            if until is not None and until(msg):
                return msg
        return None

    def heartbeat(self) -> None:
        self.conn.mav.heartbeat_send(6, 8, 0, 0, 0)

    def command(self, cmd: int, *p: float) -> int | None:
        params = [*p, *([0.0] * (7 - len(p)))]
        for attempt in range(3):
            self.conn.mav.command_long_send(self.sysid, 1, cmd, attempt, *params)
            ack = self.pump(2.0, lambda m: self._ack_for_us(m, cmd))
            if ack is not None:
                return int(ack.result)
        return None

    @staticmethod
    def _ack_for_us(m: Any, cmd: int) -> bool:
        """A COMMAND_ACK of ``cmd`` addressed to this client (system 245): another sender's
        ack of the same command is not our answer."""
        return bool(
            m.get_type() == "COMMAND_ACK" and m.command == cmd and m.target_system in (0, 245)
        )

    def set_param(self, name: str, value: float, *, int_bytewise: bool = False) -> float | None:
        wire = value
        if int_bytewise:
            wire = float(np.frombuffer(np.int32(int(value)).tobytes(), dtype=np.float32)[0])
        self.conn.mav.param_set_send(self.sysid, 1, name.encode(), wire, 6 if int_bytewise else 9)
        echo = self.pump(3.0, lambda m: m.get_type() == "PARAM_VALUE" and m.param_id == name)
        return None if echo is None else float(echo.param_value)

    def velocity(self, vn: float, ve: float, vd: float = 0.0, frame: int = 1) -> None:
        self.conn.mav.set_position_target_local_ned_send(
            0, self.sysid, 1, frame, 3527, 0, 0, 0, vn, ve, vd, 0, 0, 0, 0, 0
        )

    def position(self, n: float, e: float, d: float) -> None:
        self.conn.mav.set_position_target_local_ned_send(
            0, self.sysid, 1, 1, 3576, n, e, d, 0, 0, 0, 0, 0, 0, 0, 0
        )

    def stream(self, send: Callable[[], None], seconds: float, hz: float = 20.0) -> None:
        """Send a setpoint at ``hz`` (wall) for ``seconds`` while reading everything."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            send()
            self.pump(1.0 / hz)

    def stream_until(
        self,
        send: Callable[[], None],
        until: Callable[[Any], bool],
        timeout: float,
        hz: float = 20.0,
    ) -> Any:
        """Send a setpoint at ``hz`` (wall) until a message satisfies ``until``; that message, or
        None after ``timeout`` wall seconds. Robust to a slow reader: conditions, not snapshots."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            send()
            msg = self.pump(1.0 / hz, until)
            if msg is not None:
                return msg
        return None

    def mode(self) -> int:
        return int(self.last["HEARTBEAT"].custom_mode)


def fitted_tau(samples: list[tuple[float, float]], target: float) -> float:
    """Time constant of an exponential approach to ``target`` fitted to (t, v) samples.

    Uses only samples whose error exceeds 5 % of the step, where the exponential is well
    conditioned; the start time does not matter (it cancels in the log-linear slope).
    """
    t = np.array([s[0] for s in samples])
    err = np.abs(np.array([s[1] for s in samples]) - target)
    keep = err > 0.05 * err.max()
    slope = np.polyfit(t[keep], np.log(err[keep]), 1)[0]
    return float(-1.0 / slope)


def step_samples(log: list[Any], axis: str, target: float) -> list[tuple[float, float]]:
    """(t, v) from the last sample before the velocity started towards ``target``."""
    pts = [(m.time_boot_ms / 1000.0, float(getattr(m, axis))) for m in log]
    start = 0
    for k in range(1, len(pts)):
        if abs(pts[k][1] - pts[k - 1][1]) > 1e-3 and math.copysign(1, target - pts[k - 1][1]) == (
            math.copysign(1, pts[k][1] - pts[k - 1][1])
        ):
            start = k - 1
            break
    return pts[start:]


def free_udp_base(count: int, gap: int | None = None) -> int:
    """A base port with base..base+count-1 and base+gap..base+gap+count-1 free for UDP (the
    vehicles' send and own ports); ``gap`` defaults to 200, or ``count`` when that is larger."""
    gap = max(200, count) if gap is None else gap
    if gap < count:
        raise ValueError(f"free_udp_base: gap {gap} < count {count}: the two ranges overlap")
    for _ in range(50):
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
            probe.bind(("127.0.0.1", 0))
            base = int(probe.getsockname()[1])
        if base + gap + count > 65535:
            continue
        socks = []
        try:
            for port in [*range(base, base + count), *range(base + gap, base + gap + count)]:
                s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
                socks.append(s)
                s.bind(("127.0.0.1", port))
            return base
        except OSError:
            continue
        finally:
            for s in socks:
                s.close()
    raise RuntimeError("no free UDP port range")
