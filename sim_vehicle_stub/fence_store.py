"""A vehicle's geofence as the mission protocol carries it (mission_type FENCE): uploaded, kept,
handed back on a download, cleared. Real PX4 and ArduCopter store fence items this way
(measured on PX4 SITL: MISSION_COUNT for a fence is answered with MISSION_REQUEST_INT for each
item, then MISSION_ACK ACCEPTED; a download gives the items back). The emulator keeps the items
only: its own geofence stays the search area grown by MDM_FENCE_MARG."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from sim_vehicle_stub.mavlink import dialect as d

FENCE = d.MAV_MISSION_TYPE_FENCE
_FENCE_COMMANDS = frozenset(
    range(d.MAV_CMD_NAV_FENCE_RETURN_POINT, d.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION + 1)
)
"""5000 return point, 5001/5002 polygon vertex inclusion/exclusion, 5003/5004 circles."""
ACCEPTED: int = d.MAV_MISSION_ACCEPTED
NO_SPACE: int = d.MAV_MISSION_NO_SPACE
UNSUPPORTED: int = d.MAV_MISSION_UNSUPPORTED
MAX_ITEMS = 256
"""More is refused with NO_SPACE (PX4's dataman holds a few hundred fence points)."""


@dataclass(frozen=True)
class FenceItem:
    """One stored item, as sent back on a download."""

    command: int
    frame: int
    params: tuple[float, float, float, float]
    x: int
    y: int
    z: float


@dataclass
class FenceStore:
    """One vehicle's fence and the upload in progress (from one client at a time)."""

    items: list[FenceItem] = field(default_factory=list)
    _pending: list[FenceItem] | None = None
    _expected: int = 0

    def begin_upload(self, count: int) -> int | None:
        """A MISSION_COUNT: the result to send now (None: ask for item 0)."""
        if count == 0:
            self.items, self._pending = [], None
            return ACCEPTED
        if count > MAX_ITEMS:
            return NO_SPACE
        self._pending, self._expected = [], count
        return None

    def add_item(self, msg: Any) -> tuple[int | None, int | None]:
        """A MISSION_ITEM_INT of the upload: (the next seq to ask for, or None; the final
        result, or None while the upload goes on). Items out of order are asked for again."""
        pending = self._pending
        if pending is None:
            return None, None  # no upload in progress: ignored, as PX4 does
        if msg.seq != len(pending):
            return len(pending), None
        if msg.command not in _FENCE_COMMANDS:
            self._pending = None
            return None, UNSUPPORTED
        pending.append(
            FenceItem(
                msg.command,
                msg.frame,
                (msg.param1, msg.param2, msg.param3, msg.param4),
                msg.x,
                msg.y,
                msg.z,
            )
        )
        if len(pending) < self._expected:
            return len(pending), None
        self.items, self._pending = pending, None
        return None, ACCEPTED

    def item_message(self, target: tuple[int, int], seq: int) -> Any | None:
        """MISSION_ITEM_INT ``seq`` of the stored fence for ``target`` (system, component)."""
        if not 0 <= seq < len(self.items):
            return None
        it = self.items[seq]
        return d.MAVLink_mission_item_int_message(
            *target, seq, it.frame, it.command, 0, 1, *it.params, it.x, it.y, it.z, FENCE
        )

    def clear(self) -> None:
        self.items, self._pending = [], None
