"""The per-tick MAVLink 2 messages the companion decodes and the setpoint it encodes without
pymavlink's codec (same fields, same bytes), on the wire's framer (:mod:`mavlink_wire.frames`).

A sped-up vehicle sends each companion ~20 messages per sim second, nearly all of them
LOCAL_POSITION_NED and NAMED_VALUE_FLOAT (DEBUG_VECT on a contact, HEARTBEAT and SYS_STATUS at
1 Hz); pymavlink's byte-wise parser and message objects were a third of the companion's CPU,
and its encoder (a message object, a header object, a bytearray) a tenth. The wire's ``split``
accepts a datagram only when it is nothing but complete, unsigned MAVLink 2 frames of known
messages with good checksums; anything else (signed, MAVLink 1, truncated, garbage, a bad CRC)
is left to pymavlink, unchanged. :func:`frame` packs as pymavlink does (trailing zeros of the
payload cut, CRC with the message's extra byte), unsigned.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from mavlink_wire import frames
from mavlink_wire.frames import unpack as unpack_payload

LOCAL_POSITION_NED = mavlink2.MAVLINK_MSG_ID_LOCAL_POSITION_NED
NAMED_VALUE_FLOAT = mavlink2.MAVLINK_MSG_ID_NAMED_VALUE_FLOAT
DEBUG_VECT = mavlink2.MAVLINK_MSG_ID_DEBUG_VECT
HEARTBEAT = mavlink2.MAVLINK_MSG_ID_HEARTBEAT
SYS_STATUS = mavlink2.MAVLINK_MSG_ID_SYS_STATUS
SET_POSITION_TARGET_LOCAL_NED = mavlink2.MAVLINK_MSG_ID_SET_POSITION_TARGET_LOCAL_NED
FAST = frozenset({LOCAL_POSITION_NED, NAMED_VALUE_FLOAT, DEBUG_VECT, HEARTBEAT, SYS_STATUS})
"""Messages :func:`unpack` decodes; the rest of an accepted datagram goes frame by frame to
pymavlink."""

_UNPACKERS = {k: mavlink2.mavlink_map[k].unpacker for k in FAST}
_TEXT = frozenset(k for k in FAST if "s" in _UNPACKERS[k].format)
"""Messages with char arrays (their NULs are cut)."""
SETPOINT = mavlink2.MAVLink_set_position_target_local_ned_message.unpacker
"""SET_POSITION_TARGET_LOCAL_NED's payload in wire order: time_boot_ms, x, y, z, vx, vy, vz,
afx, afy, afz, yaw, yaw_rate, type_mask, target_system, target_component, coordinate_frame."""


def unpack(msg_id: int, frame: bytes) -> tuple[int | float | bytes, ...]:
    """Fields of a frame of a :data:`FAST` message in wire order, as pymavlink reads them:
    the payload zero-extended (MAVLink 2 cuts trailing zeros), char arrays without their NULs."""
    fields = unpack_payload(_UNPACKERS[msg_id], frame, len(frame) - 2)
    if msg_id not in _TEXT:
        return fields  # type: ignore[return-value]
    return tuple(f.rstrip(b"\x00") if isinstance(f, bytes) else f for f in fields)  # type: ignore[misc]


def frame(msg_id: int, payload: bytes, seq: int, system: int, component: int) -> bytes:
    """An unsigned MAVLink 2 frame of ``payload`` (the message's fields packed in wire order),
    byte for byte what pymavlink's ``pack`` gives."""
    return frames.frame(msg_id, frames.cut(payload), seq, system, component)
