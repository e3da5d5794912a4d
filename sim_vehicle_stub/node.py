"""A vehicle as the network sees it: its logic, encoder, stream schedule, counters and outputs."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from mavlink_wire import Verdict
from sim_vehicle_stub.encoder import Encoder
from sim_vehicle_stub.framing import LinkStats
from sim_vehicle_stub.mavlink import dialect as d
from sim_vehicle_stub.telemetry import StreamSchedule
from sim_vehicle_stub.vehicle import Vehicle

_MAX_DATAGRAM = 1400
HEARTBEAT_ID = d.MAVLINK_MSG_ID_HEARTBEAT
MISSION_CURRENT_ID = d.MAVLINK_MSG_ID_MISSION_CURRENT


@dataclass
class VehicleNode:
    """Everything the endpoints and handlers need about one vehicle."""

    vehicle: Vehicle
    encoder: Encoder
    schedule: StreamSchedule = field(default_factory=StreamSchedule)
    stats: LinkStats = field(default_factory=LinkStats)
    outputs: list[Callable[[bytes], None]] = field(default_factory=list)
    """Senders of every endpoint that carries this vehicle (UDP, TCP clients, GCS)."""
    last_heartbeat: float = -math.inf
    """Sim time of the last HEARTBEAT sent."""

    def early_heartbeat_due(self, now: float) -> bool:
        """Whether a mode/arm change may go out in a HEARTBEAT now rather than at the next
        scheduled one: at most one early beat per half interval, so a client spamming mode
        changes cannot push the rate above twice the scheduled one (real autopilots keep
        theirs fixed; the early beat lets clients see a change without waiting up to 1 s)."""
        if not self.vehicle.state_changed:
            return False
        interval = self.schedule.interval.get(HEARTBEAT_ID, 1.0)
        return now - self.last_heartbeat >= 0.5 * interval

    def take_outbox(self) -> list[Any]:
        """What the vehicle's logic queued (MISSION_CURRENT, ITEM_REACHED), emptied; a
        MISSION_CURRENT only while it streams (ArduCopter's only once a client asked:
        MissionRules.current_unasked)."""
        v = self.vehicle
        current_on = self.schedule.streams(MISSION_CURRENT_ID)
        out = [m for m in v.outbox if current_on or m.get_msgId() != MISSION_CURRENT_ID]
        v.outbox.clear()
        return out

    def authentic(self, messages: list[Any]) -> list[Any]:
        """The messages this vehicle may act on: all of them with signing off; with signing on
        (the encoder's signing state, which also signs what the vehicle sends),
        those correctly signed with a new timestamp. The others are counted (unsigned,
        bad_signature, replayed) and logged as ``signing_rejected`` at counts 1, 10, 100, ..."""
        signing = self.encoder.signing
        if signing is None:
            return messages
        out = []
        for msg in messages:
            verdict = signing.check(msg.get_msgbuf())
            if verdict is Verdict.OK:
                out.append(msg)
                continue
            stats = self.stats
            if verdict is Verdict.UNSIGNED:
                stats.unsigned += 1
            elif verdict is Verdict.BAD_SIGNATURE:
                stats.bad_signature += 1
            else:
                stats.replayed += 1
            count = stats.signing_rejected
            if count == 10 ** (len(str(count)) - 1):
                v = self.vehicle
                v.events.write(
                    v.now,
                    "signing_rejected",
                    vehicle=v.index,
                    reason=verdict.value,
                    message=msg.get_type(),
                    source=msg.get_srcSystem(),
                    count=count,
                )
        return out

    def send(self, messages: list[Any]) -> None:
        """Encode and send messages, bundled into datagrams of at most ~1400 bytes as PX4 does."""
        if messages:
            self.send_frames([self.encoder.pack(msg) for msg in messages])

    def send_frames(self, frames: list[bytes]) -> None:
        """Send encoded frames, bundled into datagrams of at most ~1400 bytes."""
        if not frames:
            return
        data = b"".join(frames)
        if len(data) <= _MAX_DATAGRAM:  # a tick's telemetry: one datagram, one join
            for out in self.outputs:
                out(data)
            return
        chunk = bytearray()
        for data in frames:
            if chunk and len(chunk) + len(data) > _MAX_DATAGRAM:
                self._emit(bytes(chunk))
                chunk = bytearray()
            chunk += data
        self._emit(bytes(chunk))

    def _emit(self, data: bytes) -> None:
        for out in self.outputs:
            out(data)
