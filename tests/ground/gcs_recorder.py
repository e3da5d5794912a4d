"""A ground station on `companion fleet --gcs`'s port, recording in a thread what a GCS sees of
each vehicle: its GLOBAL_POSITION_INT track with the mode it was in, and its HEARTBEAT's armed
flag (by system id)."""

from __future__ import annotations

import os
import socket
import threading
from dataclasses import dataclass, field

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil

ARMED = 128  # MAV_MODE_FLAG_SAFETY_ARMED


@dataclass
class Seen:
    """One vehicle as the ground station saw it."""

    track: list[tuple[float, float, float, int]] = field(default_factory=list)
    """(lat, lon, relative altitude m, custom mode of the last HEARTBEAT) of each
    GLOBAL_POSITION_INT."""
    mode: int = -1
    """custom_mode of its last HEARTBEAT."""
    armed: bool | None = None
    """Armed in its last HEARTBEAT."""
    armed_ever: bool = False


class GcsRecorder:
    """Listens on ``udpin:127.0.0.1:port`` until :meth:`close`."""

    def __init__(self, port: int) -> None:
        self.conn = mavutil.mavlink_connection(f"udpin:127.0.0.1:{port}")
        # A loaded host can leave this thread seconds behind a sped-up fleet: room to queue
        # them rather than drop them.
        self.conn.port.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 << 20)
        self.seen: dict[int, Seen] = {}
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while True:
            msg = self.conn.recv_match(type=["HEARTBEAT", "GLOBAL_POSITION_INT"], timeout=0.5)
            if msg is None and self._stop.is_set():
                return  # asked to stop, and everything queued has been read
            if msg is None or msg.get_srcComponent() != 1:
                continue
            with self._lock:
                v = self.seen.setdefault(msg.get_srcSystem(), Seen())
                if msg.get_type() == "HEARTBEAT":
                    v.armed = bool(msg.base_mode & ARMED)
                    v.mode = msg.custom_mode
                    v.armed_ever |= v.armed
                else:
                    v.track.append(
                        (msg.lat / 1e7, msg.lon / 1e7, msg.relative_alt / 1000.0, v.mode)
                    )

    def close(self) -> dict[int, Seen]:
        """Stop listening once what the socket has queued is read (the last datagrams of a
        landing may still wait there when the fleet exits); what was seen, by system id."""
        self._stop.set()
        self._thread.join(60.0)
        self.conn.close()
        with self._lock:
            return dict(self.seen)
