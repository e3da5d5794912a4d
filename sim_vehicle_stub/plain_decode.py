"""Decoding MAVLink 2 frames of scalar-only messages without pymavlink's generic decoder.

A message whose fields are all numbers (no array, no char[]) is one ``struct.unpack`` of its
zero-padded payload, reordered into the constructor's order. pymavlink's ``MAVLink.decode``
does the same after general work for arrays, strings and signing (a sixth of the emulator's
CPU in a lockstep fleet went to it, for the SET_POSITION_TARGET_LOCAL_NED every companion sends
each tick). The message built here has the attributes pymavlink's decoder gives it (header,
buffer, payload, CRC, not signed: the endpoint's own parser holds no signing key, signatures
are checked apart from decoding); ``tests/sim_vehicle_stub/test_svs_plain_decode.py`` compares
both on every such message of the dialect.
"""

from __future__ import annotations

import re
import struct
from typing import Any, NamedTuple

from mavlink_wire.crc import frame_crc
from mavlink_wire.frames import unpack
from sim_vehicle_stub.mavlink import dialect

_CRC = struct.Struct("<H")
_ARRAY_OR_CHARS = re.compile(r"\d|s")


class PlainType(NamedTuple):
    cls: Any
    unpacker: struct.Struct
    orders: tuple[int, ...]
    extra: bytes


_TYPES: dict[int, PlainType | None] = {}


def plain_type(msg_id: int) -> PlainType | None:
    """How to decode ``msg_id`` here, or None when it has an array or a char[] field (or is not
    in the dialect): pymavlink decodes those."""
    if msg_id not in _TYPES:
        cls = dialect.mavlink_map.get(msg_id)
        fmt = cls.unpacker.format if cls is not None else "s"
        _TYPES[msg_id] = (
            None
            if _ARRAY_OR_CHARS.search(fmt.lstrip("<"))
            else PlainType(cls, cls.unpacker, tuple(cls.orders), bytes((cls.crc_extra,)))
        )
    return _TYPES[msg_id]


def decode_plain(kind: PlainType, frame: bytes) -> Any:
    """The message in one whole MAVLink 2 ``frame`` of a plain type (its length already checked
    against the header); raises pymavlink's MAVError on a bad CRC, as its decoder does."""
    plen, incompat = frame[1], frame[2]
    end = 10 + plen
    crc = _CRC.unpack_from(frame, end)[0]
    if crc != frame_crc(frame[1:end] + kind.extra):
        raise dialect.MAVError(f"invalid MAVLink CRC in msgID {kind.cls.id}")
    values = unpack(kind.unpacker, frame, end)
    msg = kind.cls(*[values[k] for k in kind.orders])
    msgbuf = bytearray(frame)
    msg._msgbuf = msgbuf
    msg._payload = msgbuf[6:end]  # pymavlink's slice: from byte 6 (sic) to the CRC
    msg._crc = crc
    msg._header = dialect.MAVLink_header(
        kind.cls.id, incompat, frame[3], plen, frame[4], frame[5], frame[6]
    )
    return msg
