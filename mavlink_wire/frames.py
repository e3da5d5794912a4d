"""MAVLink 2 frames built and read without pymavlink's codec: the one framer of the emulator and
the companion (same bytes as pymavlink's ``pack``, same fields as its decoder;
``tests/wire/test_wire_frames.py`` compares them on every message of the dialect).

A frame is the magic byte 0xFD, a 9-byte header (payload length, incompat flags, compat flags,
sequence, system, component, 24-bit message id), the payload with its trailing zeros cut (one
zero byte kept when all are zero), and the CRC over header and payload followed by the message's
CRC-extra byte; with the signed flag (incompat 0x01) 13 signature bytes follow
(:mod:`mavlink_wire.signing_state`).
"""

from __future__ import annotations

import struct

from pymavlink.dialects.v20 import ardupilotmega as dialect

from mavlink_wire.crc import frame_crc

MAGIC = 0xFD
HEADER_BYTES = 10
"""Magic byte and header: the payload starts here."""
OVERHEAD = 12
"""Header and CRC of an unsigned frame."""
_HEADER = struct.Struct("<BBBBBBHB")
"""The header after the magic byte."""
_CRC = struct.Struct("<H")
EXTRA = {k: bytes((cls.crc_extra,)) for k, cls in dialect.mavlink_map.items()}
"""Each known message id's CRC-extra byte."""


def cut(payload: bytes) -> bytes:
    """A payload as MAVLink 2 sends it: trailing zeros cut, at least one byte."""
    return payload.rstrip(b"\x00") or b"\x00"


def frame(
    msg_id: int, payload: bytes, seq: int, system: int, component: int, incompat: int = 0
) -> bytes:
    """The frame of ``payload`` (already cut), without a signature even when ``incompat`` has
    the signed flag (the signer appends it)."""
    body = _HEADER.pack(len(payload), incompat, 0, seq, system, component, msg_id & 0xFFFF,
                        msg_id >> 16) + payload  # fmt: skip
    return b"\xfd" + body + _CRC.pack(frame_crc(body + EXTRA[msg_id]))


def msg_id_at(buf: bytes | bytearray, i: int) -> int:
    """The message id of the frame starting at ``buf[i]``."""
    return buf[i + 7] | (buf[i + 8] << 8) | (buf[i + 9] << 16)


def split(data: bytes) -> list[tuple[int, int, bytes]] | None:
    """(message id, source system, frame) of every frame of ``data``, or None unless ``data`` is
    nothing but whole, unsigned MAVLink 2 frames of known messages with good CRCs."""
    out = []
    i, n = 0, len(data)
    while i < n:
        if n - i < OVERHEAD or data[i] != MAGIC or data[i + 2] != 0:
            return None
        end = i + OVERHEAD + data[i + 1]
        msg_id = msg_id_at(data, i)
        extra = EXTRA.get(msg_id)
        if end > n or extra is None:
            return None
        if frame_crc(data[i + 1 : end - 2] + extra) != data[end - 2] | (data[end - 1] << 8):
            return None
        out.append((msg_id, data[i + 5], data[i:end]))
        i = end
    return out


def unpack(unpacker: struct.Struct, frame: bytes | bytearray, end: int) -> tuple[object, ...]:
    """The fields of the payload ``frame[10:end]`` in wire order, zero-extended to the message's
    size as pymavlink reads them (MAVLink 2 cuts trailing zeros; extensions may be missing)."""
    size = unpacker.size
    payload = frame[HEADER_BYTES:end]
    if len(payload) != size:
        payload = bytes(payload[:size]).ljust(size, b"\x00")
    return unpacker.unpack(payload)
