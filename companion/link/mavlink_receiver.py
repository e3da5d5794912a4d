"""The receiving half of the pymavlink link: its socket (mavlink_transport.py) and .tlog, which
datagrams are taken (the target system, from the one address it is locked to, authentically
signed), the fast path that hands a position straight to the mission's answerer, and the
events published once per read."""

from __future__ import annotations

import asyncio
import logging
import math
import time
from pathlib import Path
from typing import Any, cast

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.autopilots import UnknownAutopilotError
from companion.link import fast_frames
from companion.link.address import Address, parse_address
from companion.link.mavlink_decode import MavlinkDecoding
from companion.link.mavlink_transport import MavlinkTransport
from companion.link.messages import LinkEvent, LocalPosition, StraySource
from companion.link.tlog import TelemetryLog
from mavlink_wire import SigningState, Verdict
from mavlink_wire import frames as wire

log = logging.getLogger(__name__)

_BESIDE_POSITION = frozenset(
    {fast_frames.HEARTBEAT, fast_frames.SYS_STATUS, fast_frames.DEBUG_VECT}
)
"""What ``_answer`` takes beside the position and the signal: each second's HEARTBEAT and
SYS_STATUS, the sensor's contacts."""


class MavlinkReceiver(MavlinkDecoding):
    """Opens the link's socket and reads what the vehicle sends into events (see
    :class:`~companion.link.pymavlink_link.PymavlinkLink` for the arguments)."""

    def __init__(
        self,
        *,
        url: str,
        target_system: int,
        system_id: int,
        component_id: int,
        tlog: Path | None,
        signing_key: bytes | None,
    ) -> None:
        super().__init__()
        self.address: Address = parse_address(url)
        self.target_system = target_system
        self._mav = mavlink2.MAVLink(None, srcSystem=system_id, srcComponent=component_id)
        self._mav.robust_parsing = True
        self._tlog_path = tlog
        self._tlog: TelemetryLog | None = None
        self._net = MavlinkTransport(self.address, self._on_datagram, self._on_stream)
        """udpin: ``remote`` is the vehicle's address, locked to the first that sent the target
        system's messages (released only on reconnect, after the link was lost)."""
        self._strays: set[tuple[str, int]] = set()
        self.bad_packets = 0
        self._signing = SigningState(signing_key) if signing_key is not None else None
        self.signing_rejected = 0
        self._pending: list[LinkEvent] = []
        """Events of the datagrams read in this callback, published together at its end."""

    def describe(self) -> str:
        return self.address.url()

    async def open(self) -> None:
        if self._tlog_path is not None and self._tlog is None:
            self._tlog = TelemetryLog(self._tlog_path)
        await self._net.open()
        log.info("link open on %s for system %d", self.address.url(), self.target_system)

    async def close(self) -> None:
        self._net.close()
        if self._tlog is not None:
            self._tlog.close()
            self._tlog = None

    async def reconnect(self) -> None:
        """UDP in: keep the bound port (the vehicle sends to it again); others: re-open."""
        if self.address.scheme == "udpin" and self._net.is_open:
            self._net.remote = None  # the vehicle may come back from another port (a restart)
            self._strays.clear()
            return
        await self.close()
        await asyncio.sleep(0.1)  # let the old transport release its socket
        await self.open()

    def _on_datagram(self, data: bytes, addr: tuple[str | Any, int]) -> None:
        if self.answerer is not None and self._answer(data, addr):
            return
        self._receive(data, addr)
        self._net.drain(self._receive)
        self._publish_pending()

    def _on_stream(self, data: bytes) -> None:
        self._receive(data, None)
        self._publish_pending()

    def _answer(self, data: bytes, addr: tuple[str | Any, int]) -> bool:
        """A datagram of the locked vehicle holding one LOCAL_POSITION_NED, the sensor's signal
        (NAMED_VALUE_FLOAT), HEARTBEAT, SYS_STATUS and contacts (DEBUG_VECT) and nothing else,
        with no datagram waiting behind it: to the answerer when it says the position only
        needs steering, the other messages as events before or after it, in their order. The
        link's own bookkeeping (.tlog, stream rates, the setpoint's time_boot_ms, the
        autopilot) is :meth:`_receive`'s. False: take the events' path (nothing was changed)."""
        answerer, net = self.answerer, self._net
        if (
            answerer is None
            or net.sock is None
            or self._signing is not None
            or self._pending
            or self.alignment is not None
            or addr != net.remote
        ):
            return False
        received = time.perf_counter()
        frames = wire.split(data)
        if frames is None:
            return False
        position: tuple[int, float, float, float, float, float, float] | None = None
        signal = None
        at, component, rare = 0, 0, []
        for i, (msg_id, system, frame) in enumerate(frames):
            if system != self.target_system:
                return False
            if msg_id == fast_frames.LOCAL_POSITION_NED:
                if position is not None:  # two: the batch acts on the newest
                    return False
                position = cast(
                    tuple[int, float, float, float, float, float, float],
                    fast_frames.unpack(msg_id, frame),
                )
                at, component = i, frame[6]
            elif msg_id == fast_frames.NAMED_VALUE_FLOAT:
                _, value, name = fast_frames.unpack(msg_id, frame)
                if name == b"SENS_SIG":
                    signal = cast(float, value)
                    if not math.isfinite(signal):
                        return False  # the events' path drops and counts it
            elif msg_id in _BESIDE_POSITION:
                rare.append((i, msg_id, frame))
            else:
                return False
        if position is None:
            return False
        t, x, y, z, vx, vy, vz = position
        guard = self.guard
        if not guard.plausible_local(component, t / 1000.0, x, y, z, vx, vy, vz, received):
            return False  # the events' path drops and counts it
        if not answerer.ready(t / 1000.0, x, y):
            return False
        if net.waiting() is not False:  # another datagram: the batch acts on the newest only
            return False
        if self._tlog is not None:
            for _, _, frame in frames:
                self._tlog.write(frame)
        before: list[LinkEvent] = []
        after: list[LinkEvent] = []
        for i, msg_id, frame in rare:
            if (event := self._event(msg_id, frame, received)) is not None:
                (before if i < at else after).append(event)
        guard.local(component, t / 1000.0, x, y, z, vx, vy, vz, received)  # taken: plausible
        self._time_ms = t
        self.streams.note("LOCAL_POSITION_NED", t / 1000.0)
        pos = LocalPosition(t / 1000.0, x, y, z, vx, vy, vz, received)
        answerer.answer(pos, signal, before, after)
        return True

    def _publish_pending(self) -> None:
        batch = self._pending
        if batch:
            self._pending = []
            self.publish(batch)

    def _receive(self, data: bytes, addr: tuple[str | Any, int] | None) -> None:
        received = time.perf_counter()
        frames = wire.split(data) if self._signing is None and addr is not None else None
        if frames is None:
            self._accept(data, addr, received)
            return
        for msg_id, system, frame in frames:  # the same events, fewer Python steps
            if msg_id not in fast_frames.FAST:
                self._accept(frame, addr, received)
                continue
            self.heard.add(system)
            if system != self.target_system or not self._from_vehicle(addr):
                continue
            if self._tlog is not None:
                self._tlog.write(frame)
            if (event := self._event(msg_id, frame, received)) is not None:
                self._pending.append(event)

    def _accept(self, data: bytes, addr: tuple[str | Any, int] | None, received: float) -> None:
        try:
            messages = self._mav.parse_buffer(data)
        except Exception as exc:  # a broken packet must never take the companion down
            self.bad_packets += 1
            log.debug("unparsable packet from %s: %s", addr, exc)
            return
        for msg in messages or ():
            if msg.get_type() == "BAD_DATA":
                self.bad_packets += 1
                continue
            system = msg.get_srcSystem()
            self.heard.add(system)
            if system != self.target_system:
                continue
            if self._signing is not None and not self._authentic(self._signing, msg):
                continue
            if not self._from_vehicle(addr):
                continue
            if self._tlog is not None:
                self._tlog.write(msg.get_msgbuf())
            try:
                event = self._translate(msg, received)
            except (UnknownAutopilotError, ValueError) as exc:
                self.guard.unreadable(msg.get_type(), exc)
                continue
            if event is not None:
                self._pending.append(event)

    def _from_vehicle(self, addr: tuple[str | Any, int] | None) -> bool:
        """udpin: lock to the first address that speaks for the target system; another
        address with the same id is dropped and reported once (a second vehicle or emulator
        with a clashing id must never be taken for ours)."""
        if addr is None or self.address.scheme != "udpin":
            return True
        source = (str(addr[0]), int(addr[1]))
        remote = self._net.remote
        if remote is None:
            self._net.remote = source
            log.info("system %d locked to %s:%d", self.target_system, *source)
            return True
        if source == remote:
            return True
        if source not in self._strays:
            self._strays.add(source)
            locked = f"{remote[0]}:{remote[1]}"
            log.warning(
                "ignoring another sender of system %d at %s:%d (locked to %s)",
                self.target_system,
                *source,
                locked,
            )
            self._pending.append(StraySource(f"{source[0]}:{source[1]}", locked))
        return False

    def _authentic(self, signing: SigningState, msg: Any) -> bool:
        verdict = signing.check(msg.get_msgbuf())
        if verdict is Verdict.OK:
            return True
        self.signing_rejected += 1
        n = self.signing_rejected
        if n == 10 ** (len(str(n)) - 1):
            log.warning(
                "dropped %s from system %d: %s (%d dropped so far)",
                msg.get_type(),
                self.target_system,
                verdict.value,
                n,
            )
        return False
