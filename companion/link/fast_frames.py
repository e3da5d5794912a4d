"""The per-tick MAVLink 2 messages decoded and the setpoint encoded without pymavlink's codec
(same fields, same bytes).

A sped-up vehicle sends each companion ~20 messages per sim second, nearly all of them
LOCAL_POSITION_NED and NAMED_VALUE_FLOAT (DEBUG_VECT on a contact, HEARTBEAT and SYS_STATUS at
1 Hz); pymavlink's byte-wise parser and message objects were a third of the companion's CPU,
and its encoder (a message object, a header object, a bytearray) a tenth. :func:`split` accepts
a datagram only when it is nothing but complete, unsigned MAVLink 2 frames of known messages
with good checksums; anything else (signed, MAVLink 1, truncated, garbage, a bad CRC) is left
to pymavlink, unchanged. :func:`frame` packs as pymavlink does (trailing zeros of the payload
cut, CRC with the message's extra byte), unsigned.
"""

from __future__ import annotations

import struct

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from mavlink_signing.frame_crc import frame_crc

LOCAL_POSITION_NED = mavlink2.MAVLINK_MSG_ID_LOCAL_POSITION_NED
NAMED_VALUE_FLOAT = mavlink2.MAVLINK_MSG_ID_NAMED_VALUE_FLOAT
DEBUG_VECT = mavlink2.MAVLINK_MSG_ID_DEBUG_VECT
HEARTBEAT = mavlink2.MAVLINK_MSG_ID_HEARTBEAT
SYS_STATUS = mavlink2.MAVLINK_MSG_ID_SYS_STATUS
SET_POSITION_TARGET_LOCAL_NED = mavlink2.MAVLINK_MSG_ID_SET_POSITION_TARGET_LOCAL_NED
FAST = frozenset({LOCAL_POSITION_NED, NAMED_VALUE_FLOAT, DEBUG_VECT, HEARTBEAT, SYS_STATUS})
"""Messages :func:`unpack` decodes; the rest of an accepted datagram goes frame by frame to
pymavlink."""

_EXTRA = {k: bytes((cls.crc_extra,)) for k, cls in mavlink2.mavlink_map.items()}
_UNPACKERS = {k: mavlink2.mavlink_map[k].unpacker for k in FAST}
_TEXT = frozenset(k for k in FAST if "s" in _UNPACKERS[k].format)
"""Messages with char arrays (their NULs are cut)."""
_CRC = struct.Struct("<H")
_HEADER = struct.Struct("<BBBBBBBHB")
SETPOINT = mavlink2.MAVLink_set_position_target_local_ned_message.unpacker
"""SET_POSITION_TARGET_LOCAL_NED's payload in wire order: time_boot_ms, x, y, z, vx, vy, vz,
afx, afy, afz, yaw, yaw_rate, type_mask, target_system, target_component, coordinate_frame."""


def split(data: bytes) -> list[tuple[int, int, bytes]] | None:
    """(message id, source system, frame) of every frame, or None to leave it to pymavlink."""
    out = []
    i, n = 0, len(data)
    while i < n:
        if n - i < 12 or data[i] != 0xFD or data[i + 2] != 0:  # MAVLink 2, no signature
            return None
        end = i + 12 + data[i + 1]
        msg_id = data[i + 7] | (data[i + 8] << 8) | (data[i + 9] << 16)
        extra = _EXTRA.get(msg_id)
        if end > n or extra is None:
            return None
        if frame_crc(data[i + 1 : end - 2] + extra) != data[end - 2] | (data[end - 1] << 8):
            return None
        out.append((msg_id, data[i + 5], data[i:end]))
        i = end
    return out


def unpack(msg_id: int, frame: bytes) -> tuple[int | float | bytes, ...]:
    """Fields of a frame of a :data:`FAST` message in wire order, as pymavlink reads them:
    the payload zero-extended (MAVLink 2 cuts trailing zeros), char arrays without their NULs."""
    unpacker = _UNPACKERS[msg_id]
    size = unpacker.size
    payload = frame[10:-2]
    if len(payload) != size:
        payload = payload[:size].ljust(size, b"\x00")
    fields = unpacker.unpack(payload)
    if msg_id not in _TEXT:
        return fields  # type: ignore[no-any-return]
    return tuple(f.rstrip(b"\x00") if isinstance(f, bytes) else f for f in fields)


def frame(msg_id: int, payload: bytes, seq: int, system: int, component: int) -> bytes:
    """An unsigned MAVLink 2 frame of ``payload`` (the message's fields packed in wire order),
    byte for byte what pymavlink's ``pack`` gives."""
    payload = payload.rstrip(b"\x00") or payload[:1]
    header = _HEADER.pack(0xFD, len(payload), 0, 0, seq, system, component, msg_id & 0xFFFF,
                          msg_id >> 16)  # fmt: skip
    body = header + payload
    return body + _CRC.pack(frame_crc(body[1:] + _EXTRA[msg_id]))
