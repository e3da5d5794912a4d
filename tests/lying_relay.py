"""A link that lies: a relay between a vehicle and its companion that corrupts, drops,
duplicates, reorders and delays the vehicle's messages, slips in broken telemetry from the
vehicle's own address and system id (and a second component with its own clock), and checks
every setpoint the companion sends back.

    vehicle (emulator: it sends to ``vehicle_port``; SITL: ``tcp:HOST:PORT``)
        <-> relay <->  companion (udpin on ``companion_port``: the relay is its vehicle)

Every count the tests assert is here: ``injected`` (per corruption kind), ``setpoints`` and
``bad_setpoints`` (non-finite or faster than ``max_speed``, with the message's fields).
"""

from __future__ import annotations

import contextlib
import math
import os
import random
import selectors
import socket
import threading
import time
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

os.environ.setdefault("MAVLINK20", "1")
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

KINDS = ("nan", "inf", "huge", "jump", "latlon", "clock_back", "second_component")
"""Broken telemetry the relay slips in, in turn: LOCAL_POSITION_NED with NaN, inf or 1e38
positions and velocities, a 100 km jump, GLOBAL_POSITION_INT at the integer limits, a position
35 s behind the vehicle's clock (component 1), and a second component (id 2) whose clock runs
500 s ahead."""
FAULTS = ("drop", "duplicate", "reorder", "delay")
"""What the relay does to the vehicle's own datagrams, each with ``fault_chance``."""
VELOCITY_MASK = 3527


@dataclass
class RelayStats:
    injected: Counter[str] = field(default_factory=Counter)
    faults: Counter[str] = field(default_factory=Counter)
    forwarded: int = 0
    setpoints: int = 0
    bad_setpoints: list[dict[str, Any]] = field(default_factory=list)


class LyingRelay:
    """Start with :meth:`start`, stop with :meth:`stop` (or use it as a context manager).

    ``kinds``: corruptions slipped in, round-robin at ``rate_hz`` (wall), from the companion's
    first message on (a companion listens then; ``rate_hz`` 0 stops them); ``fault_chance``:
    chance of each transport fault per vehicle datagram; ``max_speed``: the profile's speed
    (a velocity setpoint faster than it is bad). ``silent``: forward nothing either way (the
    link dies); ``all_bad``: every LOCAL_POSITION_NED of the vehicle goes out with NaN
    positions (the estimator failed). ``vehicle``: (host, port) of a TCP vehicle to connect
    to (ArduCopter SITL's SERIAL0), or the UDP port to take for a vehicle that sends there
    (PX4 SITL's offboard link, 14540+i), or None: a free UDP port (``vehicle_port``, where
    the emulator's vehicle is told to send).
    """

    def __init__(
        self,
        companion_port: int,
        *,
        sysid: int = 1,
        vehicle: tuple[str, int] | int | None = None,
        kinds: tuple[str, ...] = KINDS,
        rate_hz: float = 10.0,
        fault_chance: float = 0.0,
        max_speed: float = 20.0,
        seed: int = 0,
    ) -> None:
        self.companion = ("127.0.0.1", companion_port)
        self.sysid = sysid
        self.kinds = kinds
        self.rate_hz = rate_hz
        self.fault_chance = fault_chance
        self.max_speed = max_speed
        self.stats = RelayStats()
        self.silent = False
        self.all_bad = False
        self.companion_types: frozenset[str] | None = None
        """Only the companion's messages of these types reach the vehicle (None: all): e.g.
        its HEARTBEAT alone, so its setpoints and commands stop while it seems alive."""
        self.alt_offset = 0.0
        """Metres added to the altitude (-z) of every LOCAL_POSITION_NED of the vehicle: a
        vehicle that reads as off its altitude layer."""
        self._rng = random.Random(seed)
        self._sel = selectors.DefaultSelector()
        self._to_companion = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._to_companion.bind(("127.0.0.1", 0))
        self._vehicle_tcp = vehicle if isinstance(vehicle, tuple) else None
        self._from_vehicle: socket.socket | None = None
        self.vehicle_port = 0
        if self._vehicle_tcp is None:
            udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            udp.bind(("127.0.0.1", vehicle if isinstance(vehicle, int) else 0))
            self._from_vehicle = udp
            self.vehicle_port = udp.getsockname()[1]
        self._vehicle_addr: tuple[str, int] | None = None
        self._parse_in = mavlink2.MAVLink(None)
        self._parse_in.robust_parsing = True
        self._parse_out = mavlink2.MAVLink(None)
        self._parse_out.robust_parsing = True
        self._liar = mavlink2.MAVLink(None, srcSystem=sysid, srcComponent=1)
        self._other = mavlink2.MAVLink(None, srcSystem=sysid, srcComponent=2)
        self._last: Any = None
        """The vehicle's newest LOCAL_POSITION_NED (what the lies are made from)."""
        self._companion_heard = False
        """Lies start once the companion has spoken (it listens): each one sent is one it read."""
        self._held: bytes | None = None
        self._delayed: list[tuple[float, bytes]] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="lying-relay", daemon=True)

    def start(self) -> LyingRelay:
        if self._vehicle_tcp is not None:
            self._from_vehicle = socket.create_connection(self._vehicle_tcp, timeout=10)
        assert self._from_vehicle is not None
        self._from_vehicle.setblocking(False)
        self._sel.register(self._from_vehicle, selectors.EVENT_READ, "vehicle")
        self._sel.register(self._to_companion, selectors.EVENT_READ, "companion")
        self._thread.start()
        return self

    def connected(self) -> bool:
        """:meth:`start`, False while the vehicle's TCP port refuses it (a SITL still booting):
        for ``wait_until(relay.connected, ...)``."""
        try:
            self.start()
        except OSError:
            return False
        return True

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=5)
        for s in (self._from_vehicle, self._to_companion):
            if s is not None:
                s.close()

    def __enter__(self) -> LyingRelay:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    # -- the loop ------------------------------------------------------------------------

    def _run(self) -> None:
        next_lie, turn = time.monotonic() + 1.0, 0
        while not self._stop.is_set():
            for key, _ in self._sel.select(timeout=0.01):
                try:
                    if key.data == "vehicle":
                        self._vehicle_data()
                    else:
                        self._companion_data()
                except (BlockingIOError, InterruptedError):
                    continue
                except OSError:
                    continue
            now = time.monotonic()
            self._release(now)
            lying = self.kinds and self.rate_hz > 0 and self._companion_heard
            if lying and now >= next_lie and not self.silent:
                next_lie = now + 1.0 / self.rate_hz
                if self._last is not None:
                    kind = self.kinds[turn % len(self.kinds)]
                    turn += 1
                    self._send_companion(self._lie(kind))
                    self.stats.injected[kind] += 1

    def _vehicle_data(self) -> None:
        sock = self._from_vehicle
        assert sock is not None
        if self._vehicle_tcp is None:
            data, addr = sock.recvfrom(65536)
            self._vehicle_addr = addr
        else:
            data = sock.recv(65536)
        for msg in self._parse_in.parse_buffer(data) or ():
            if msg.get_type() == "BAD_DATA":
                continue
            self._from_vehicle_msg(msg)

    def _from_vehicle_msg(self, msg: Any) -> None:
        buf = bytes(msg.get_msgbuf())
        if msg.get_type() == "LOCAL_POSITION_NED" and msg.get_srcComponent() == 1:
            self._last = msg
            if self.all_bad:
                buf = self._local(
                    self._liar,
                    msg.time_boot_ms,
                    math.nan,
                    math.nan,
                    math.nan,
                    msg.vx,
                    msg.vy,
                    msg.vz,
                )
            elif self.alt_offset:
                buf = self._local(
                    self._liar,
                    msg.time_boot_ms,
                    msg.x,
                    msg.y,
                    msg.z - self.alt_offset,
                    msg.vx,
                    msg.vy,
                    msg.vz,
                )
        if self.silent:
            return
        self.stats.forwarded += 1
        if self.fault_chance <= 0 or self._rng.random() >= self.fault_chance:
            self._send_companion(buf)
            return
        fault = self._rng.choice(FAULTS)
        self.stats.faults[fault] += 1
        if fault == "duplicate":
            self._send_companion(buf)
            self._send_companion(buf)
        elif fault == "reorder":  # goes out after the next one
            if self._held is not None:
                self._send_companion(self._held)
            self._held = buf
        elif fault == "delay":
            self._delayed.append((time.monotonic() + self._rng.uniform(0.05, 0.5), buf))

    def _release(self, now: float) -> None:
        if self._held is not None and self._rng.random() < 0.2:
            self._send_companion(self._held)
            self._held = None
        due = [b for t, b in self._delayed if t <= now]
        self._delayed = [(t, b) for t, b in self._delayed if t > now]
        for buf in due:
            self._send_companion(buf)

    def _send_companion(self, buf: bytes) -> None:
        if self.silent:
            return
        with contextlib.suppress(OSError):
            self._to_companion.sendto(buf, self.companion)

    def _companion_data(self) -> None:
        data, _ = self._to_companion.recvfrom(65536)
        self._companion_heard = True
        msgs = self._parse_out.parse_buffer(data) or []
        for msg in msgs:
            if msg.get_type() == "SET_POSITION_TARGET_LOCAL_NED":
                self._check(msg)
        if self.silent:
            return
        if self.companion_types is not None:
            wanted = [m for m in msgs if m.get_type() in self.companion_types]
            data = b"".join(bytes(m.get_msgbuf()) for m in wanted)
            if not data:
                return
        sock = self._from_vehicle
        assert sock is not None
        if self._vehicle_tcp is not None:
            sock.sendall(data)
        elif self._vehicle_addr is not None:
            sock.sendto(data, self._vehicle_addr)

    def _check(self, msg: Any) -> None:
        self.stats.setpoints += 1
        values = (msg.x, msg.y, msg.z, msg.vx, msg.vy, msg.vz)
        bad = not all(math.isfinite(v) for v in values)
        if msg.type_mask == VELOCITY_MASK:
            bad = bad or math.hypot(msg.vx, msg.vy) > self.max_speed * (1 + 1e-5)
        if bad:
            self.stats.bad_setpoints.append(msg.to_dict())

    # -- the lies --------------------------------------------------------------------------

    def _local(
        self, mav: Any, t_ms: int, x: float, y: float, z: float, vx: float, vy: float, vz: float
    ) -> bytes:
        return bytes(mav.local_position_ned_encode(t_ms, x, y, z, vx, vy, vz).pack(mav))

    def _lie(self, kind: str) -> bytes:
        p = self._last
        t = p.time_boot_ms
        if kind == "nan":
            return self._local(self._liar, t, math.nan, math.nan, p.z, math.nan, math.nan, 0.0)
        if kind == "inf":
            return self._local(self._liar, t, math.inf, -math.inf, p.z, math.inf, 0.0, 0.0)
        if kind == "huge":
            return self._local(self._liar, t, 1e38, -1e38, p.z, 1e38, 1e38, 0.0)
        if kind == "jump":
            return self._local(self._liar, t, p.x + 1e5, p.y, p.z, p.vx, p.vy, p.vz)
        if kind == "latlon":
            mav = self._liar
            msg = mav.global_position_int_encode(t, 2**31 - 1, -(2**31), 0, 0, 0, 0, 0, 0)
            return bytes(msg.pack(mav))
        if kind == "clock_back":
            return self._local(self._liar, max(t - 35_000, 0), p.x, p.y, p.z, p.vx, p.vy, p.vz)
        if kind == "second_component":
            return self._local(self._other, t + 500_000, p.x + 50.0, p.y, p.z, p.vx, p.vy, p.vz)
        raise ValueError(f"unknown corruption kind {kind!r}; known: {', '.join(KINDS)}")
