"""A blocking pymavlink session with one vehicle: wait for messages, send commands, collect acks."""

from __future__ import annotations

import os
import time
from collections import defaultdict
from typing import Any

os.environ.setdefault("MAVLINK20", "1")

from pymavlink import mavutil

from mavlink_conformance.errors import ConformanceError

__all__ = ["LinkClosedError", "Session", "mavutil"]


_STAMPED = ("ATTITUDE", "GLOBAL_POSITION_INT", "LOCAL_POSITION_NED", "SYSTEM_TIME")
"""Messages that carry the vehicle's ``time_boot_ms``."""


class LinkClosedError(ConformanceError, ConnectionError):
    """The vehicle closed the connection (TCP EOF or reset): nothing more can be checked."""


def _closed(what: str) -> Any:
    def handler() -> None:
        raise LinkClosedError(f"{what} on the vehicle link: the autopilot closed it or died")

    return handler


class Session:
    """Talks to the vehicle ``sysid`` (learned from its first autopilot heartbeat when None)."""

    def __init__(
        self, address: str, *, sysid: int | None, source_system: int, timeout: float
    ) -> None:
        self.conn: Any = mavutil.mavlink_connection(
            address, source_system=source_system, source_component=190, autoreconnect=False
        )
        # pymavlink reconnects (and prints "EOF on TCP socket") on every read after the peer
        # closed; a check must stop at once instead of spinning on a dead link.
        if hasattr(self.conn, "handle_eof"):
            self.conn.handle_eof = _closed("EOF")
            self.conn.handle_disconnect = _closed("connection reset")
        self.speed = 1.0
        """Vehicle seconds per wall second (SITL speed-up), measured with TIMESYNC."""
        self.hostile = False
        """Whether checks may send NaN / out-of-range values (can crash an autopilot)."""
        self.mavlink2: bool | None = None
        """Whether the vehicle's first heartbeat came in a MAVLink 2 frame."""
        self.sysid = sysid
        self.compid = 1
        self.timeout = timeout
        self.heartbeat: Any = None
        self.seen: dict[str, list[tuple[float, Any]]] = defaultdict(list)
        """Every message from the vehicle by type, with the wall time it arrived."""

    @property
    def mav(self) -> Any:
        return self.conn.mav

    def close(self) -> None:
        self.conn.close()

    def _from_vehicle(self, msg: Any) -> bool:
        if msg.get_type() == "BAD_DATA":
            return False
        if self.sysid is None:
            if (
                msg.get_type() != "HEARTBEAT"
                or msg.autopilot == mavutil.mavlink.MAV_AUTOPILOT_INVALID
            ):
                return False
            if msg.type in (
                mavutil.mavlink.MAV_TYPE_GCS,
                mavutil.mavlink.MAV_TYPE_ONBOARD_CONTROLLER,
            ):
                return False
            self.sysid = msg.get_srcSystem()
        return bool(msg.get_srcSystem() == self.sysid)

    def recv(self, types: set[str] | None, timeout: float, cond: Any = None) -> Any:
        """The next message from the vehicle of one of ``types`` satisfying ``cond``, or None."""
        deadline = time.monotonic() + timeout
        while (left := deadline - time.monotonic()) > 0:
            msg = self.conn.recv_match(blocking=True, timeout=min(left, 0.2))
            if msg is None or not self._from_vehicle(msg):
                continue
            kind = msg.get_type()
            self.seen[kind].append((time.monotonic(), msg))
            if kind == "HEARTBEAT" and msg.get_srcComponent() == self.compid:
                self.heartbeat = msg
                if self.mavlink2 is None:
                    self.mavlink2 = msg.get_msgbuf()[0] == 0xFD
            if (types is None or kind in types) and (cond is None or cond(msg)):
                return msg
        return None

    def collect(self, seconds: float) -> None:
        """Read everything for ``seconds``."""
        self.recv({"__never__"}, seconds)

    def send_heartbeat(self) -> None:
        self.mav.heartbeat_send(
            mavutil.mavlink.MAV_TYPE_GCS, mavutil.mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0
        )

    def vehicle_seconds(self, start: float, end: float) -> float:
        """Vehicle seconds between two wall arrival times, read from the vehicle's own clock
        (``time_boot_ms`` of the messages that arrived between them) so that a vehicle or a
        reader that fell behind wall time (a loaded machine) is measured in its own time; the
        wall span times the TIMESYNC speed-up when fewer than two stamped messages arrived."""
        boot: list[int] = [
            m.time_boot_ms
            for kind in _STAMPED
            for t, m in self.seen.get(kind, ())
            if start <= t <= end
        ]
        if len(boot) >= 2 and max(boot) > min(boot):
            return (max(boot) - min(boot)) / 1000.0
        return (end - start) * self.speed

    def command(self, command: int, *params: float, tries: int = 3) -> Any:
        """Send COMMAND_LONG (retrying) and return its COMMAND_ACK, or None."""
        p = [*params, *([0.0] * (7 - len(params)))]
        assert self.sysid is not None
        for attempt in range(tries):
            self.mav.command_long_send(self.sysid, self.compid, command, attempt, *p)
            ack = self.recv({"COMMAND_ACK"}, self.timeout / tries, lambda m: m.command == command)
            if ack is not None:
                return ack
        return None
