"""MAVLink encoding for one vehicle: its own system id, component 1 and sequence counter.

Messages without numeric arrays take a fast path (one struct.pack) that produces the same bytes
as pymavlink's own packer; the rest go through pymavlink for their payload. Every frame is built
by the wire's framer (:func:`mavlink_wire.frames.frame`); with a signing state every frame is
signed (MAVLink 2 signing), whichever path built it.
"""

from __future__ import annotations

import re
from typing import Any

from mavlink_wire import SigningState
from mavlink_wire.frames import cut
from mavlink_wire.frames import frame as wire_frame
from sim_vehicle_stub.mavlink import dialect

_COUNTED = re.compile(r"(\d+)([a-zA-Z?])")
_FAST: dict[type, tuple[str, ...] | None] = {}


def _fast_fields(cls: type) -> tuple[str, ...] | None:
    """Field order for the fast path, or None when the message has numeric arrays."""
    if cls not in _FAST:
        # A repeat count before any struct code but "s" (char[]) means a numeric array.
        fmt = cls.unpacker.format  # type: ignore[attr-defined]
        arrays = any(code != "s" for _, code in _COUNTED.findall(fmt))
        _FAST[cls] = None if arrays else tuple(cls.ordered_fieldnames)  # type: ignore[attr-defined]
    return _FAST[cls]


class Encoder:
    """Packs messages as system ``sysid``, component 1, numbering them in sequence; signs them
    when given a signing state."""

    def __init__(self, sysid: int, compid: int = 1, signing: SigningState | None = None) -> None:
        self.mav = dialect.MAVLink(None, srcSystem=sysid, srcComponent=compid)
        self.sysid, self.compid = sysid, compid
        self.signing = signing
        self._incompat = 0 if signing is None else 1

    def pack(self, msg: Any) -> bytes:
        fields = _fast_fields(type(msg))
        if fields is None:
            # pymavlink packs the payload (arrays, trailing zeros cut); frame() adds the rest.
            payload: bytes = msg.pack(self.mav)[10:-2]
            return self.frame(type(msg).id, payload)
        values = [getattr(msg, f) for f in fields]
        values = [v.encode() if isinstance(v, str) else v for v in values]
        # Class attributes: a field may be called "id" (STATUSTEXT).
        return self.frame(type(msg).id, cut(msg.unpacker.pack(*values)))

    def frame(self, msg_id: int, payload: bytes) -> bytes:
        """A MAVLink 2 frame around a payload whose trailing zeros are already cut, numbered
        next in this vehicle's sequence."""
        mav = self.mav
        seq = mav.seq
        mav.seq = (seq + 1) & 0xFF
        data = wire_frame(msg_id, payload, seq, self.sysid, self.compid, self._incompat)
        if self.signing is not None:
            data += self.signing.signature(data)
        return data
