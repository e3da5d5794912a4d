"""The per-tick MAVLink 2 messages decoded without pymavlink's parser (same fields, same bytes).

A sped-up vehicle sends each companion ~20 messages per sim second, nearly all of them
LOCAL_POSITION_NED, NAMED_VALUE_FLOAT and DEBUG_VECT; pymavlink's byte-wise parser and message
objects were a third of the companion's CPU. :func:`split` accepts a datagram only when it is
nothing but complete, unsigned MAVLink 2 frames of known messages with good checksums; anything
else (signed, MAVLink 1, truncated, garbage, a bad CRC) is left to pymavlink, unchanged.
"""

from __future__ import annotations

import struct

from pymavlink.dialects.v20 import ardupilotmega as mavlink2
from pymavlink.generator import mavcrc

LOCAL_POSITION_NED = mavlink2.MAVLINK_MSG_ID_LOCAL_POSITION_NED
NAMED_VALUE_FLOAT = mavlink2.MAVLINK_MSG_ID_NAMED_VALUE_FLOAT
DEBUG_VECT = mavlink2.MAVLINK_MSG_ID_DEBUG_VECT
FAST = frozenset({LOCAL_POSITION_NED, NAMED_VALUE_FLOAT, DEBUG_VECT})
"""Messages :func:`unpack` decodes; the rest of an accepted datagram goes frame by frame to
pymavlink."""

_CRC_EXTRA = {k: cls.crc_extra for k, cls in mavlink2.mavlink_map.items()}
_UNPACKERS = {k: mavlink2.mavlink_map[k].unpacker for k in FAST}
_CRC = struct.Struct("<H")


def _crc16(data: bytes) -> int:
    if mavcrc.mcrf4xx is not None:
        return int(mavcrc.mcrf4xx(data))
    return int(mavcrc.x25crc(data).crc)


def split(data: bytes) -> list[tuple[int, int, bytes]] | None:
    """(message id, source system, frame) of every frame, or None to leave it to pymavlink."""
    out = []
    i, n = 0, len(data)
    while i < n:
        if n - i < 12 or data[i] != 0xFD or data[i + 2] != 0:  # MAVLink 2, no signature
            return None
        end = i + 12 + data[i + 1]
        msg_id = data[i + 7] | (data[i + 8] << 8) | (data[i + 9] << 16)
        extra = _CRC_EXTRA.get(msg_id)
        if end > n or extra is None:
            return None
        frame = data[i:end]
        if _crc16(frame[1:-2] + bytes((extra,))) != _CRC.unpack_from(frame, len(frame) - 2)[0]:
            return None
        out.append((msg_id, frame[5], frame))
        i = end
    return out


def unpack(msg_id: int, frame: bytes) -> tuple[int | float | bytes, ...]:
    """Fields of a frame of a :data:`FAST` message in wire order, as pymavlink reads them:
    the payload zero-extended (MAVLink 2 cuts trailing zeros), char arrays without their NULs."""
    unpacker = _UNPACKERS[msg_id]
    payload = frame[10:-2][: unpacker.size].ljust(unpacker.size, b"\x00")
    fields = unpacker.unpack(payload)
    return tuple(f.rstrip(b"\x00") if isinstance(f, bytes) else f for f in fields)
