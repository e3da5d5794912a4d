"""MAVLink encoding for one vehicle: its own system id, component 1 and sequence counter.

Messages without numeric arrays take a fast path (one struct.pack, fastcrc when installed) that
produces the same bytes as pymavlink's own packer; the rest go through pymavlink. With a signing
state every frame is signed (MAVLink 2 signing), whichever path built it.
"""

from __future__ import annotations

import re
import struct
from typing import Any

from mavlink_signing import SigningState
from mavlink_signing.frame_crc import frame_crc
from sim_vehicle_stub.mavlink import dialect

_HEADER = struct.Struct("<BBBBBBHB")
"""A MAVLink 2 header after its magic byte: length, flags, seq, system, component, 24-bit id."""
_CRC = struct.Struct("<H")
_EXTRA = [bytes((i,)) for i in range(256)]
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
            return self.frame(type(msg).id, type(msg).crc_extra, payload)
        values = [getattr(msg, f) for f in fields]
        values = [v.encode() if isinstance(v, str) else v for v in values]
        payload = msg.unpacker.pack(*values).rstrip(b"\x00") or b"\x00"
        # Class attributes: a field may be called "id" (STATUSTEXT).
        return self.frame(type(msg).id, type(msg).crc_extra, payload)

    def frame(self, msg_id: int, crc_extra: int, payload: bytes) -> bytes:
        """A MAVLink 2 frame around a payload whose trailing zeros are already cut."""
        mav = self.mav
        seq = mav.seq
        mav.seq = (seq + 1) & 0xFF
        body = _HEADER.pack(
            len(payload), self._incompat, 0, seq, self.sysid, self.compid, msg_id & 0xFFFF,
            msg_id >> 16,
        ) + payload  # fmt: skip
        data = b"\xfd" + body + _CRC.pack(frame_crc(body + _EXTRA[crc_extra]))
        if self.signing is not None:
            data += self.signing.signature(data)
        return data
