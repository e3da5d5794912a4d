"""The wire's framer against pymavlink's codec on every message of the dialect: the same bytes
built (by the wire, by the emulator's encoder, by the companion's), the same frames split and
the same fields read; anything not a clean unsigned MAVLink 2 datagram left to pymavlink."""

from __future__ import annotations

import random
import re
import struct
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.link import fast_frames
from mavlink_wire import frames as wire
from sim_vehicle_stub.encoder import Encoder

MESSAGES = sorted(mavlink2.mavlink_map)
_TOKEN = re.compile(r"(\d*)([a-zA-Z?])")
_BITS = {"b": 8, "h": 16, "i": 32, "q": 64}


def _scalar(code: str, rng: random.Random) -> Any:
    if rng.random() < 0.25:
        return 0.0 if code in "fd" else 0
    if code in "fd":
        return struct.unpack("<f", struct.pack("<f", rng.uniform(-1e6, 1e6)))[0]
    bits = _BITS[code.lower()]
    if code.isupper():
        return rng.randrange(0, 2**bits)
    return rng.randrange(-(2 ** (bits - 1)), 2 ** (bits - 1))


def _field(count: str, code: str, rng: random.Random) -> Any:
    if code == "s":
        return bytes(rng.randrange(33, 127) for _ in range(rng.randrange(int(count) + 1)))
    if count:
        return [_scalar(code, rng) for _ in range(int(count))]
    return _scalar(code, rng)


def _random_message(cls: Any, rng: random.Random) -> Any:
    tokens = _TOKEN.findall(cls.unpacker.format.lstrip("<"))
    wire_values = dict(
        zip(cls.ordered_fieldnames, (_field(n, c, rng) for n, c in tokens), strict=True)
    )
    return cls(*[wire_values[name] for name in cls.fieldnames])


def _packed(msg: Any, seq: int, system: int, component: int) -> bytes:
    mav = mavlink2.MAVLink(None, srcSystem=system, srcComponent=component)
    mav.seq = seq
    return bytes(msg.pack(mav))


@pytest.mark.parametrize("msg_id", MESSAGES)
def test_the_wire_builds_and_reads_what_pymavlink_does(msg_id: int) -> None:
    cls = mavlink2.mavlink_map[msg_id]
    rng = random.Random(msg_id)
    for k in range(20):
        msg = _random_message(cls, rng)
        seq, system, component = rng.randrange(256), rng.randrange(1, 256), rng.randrange(256)
        expected = _packed(msg, seq, system, component)
        payload = expected[wire.HEADER_BYTES : -2]
        assert wire.frame(msg_id, payload, seq, system, component) == expected, k
        assert fast_frames.frame(msg_id, payload, seq, system, component) == expected, k
        assert wire.split(expected) == [(msg_id, system, expected)], k
        assert wire.split(expected + expected) == [(msg_id, system, expected)] * 2, k
        decoded = mavlink2.MAVLink(None).decode(bytearray(expected))
        fields = wire.unpack(cls.unpacker, expected, len(expected) - 2)
        assert decoded.get_msgbuf() == expected
        if "s" not in cls.unpacker.format and not any(cls.array_lengths):
            assert list(fields) == [getattr(decoded, f) for f in cls.ordered_fieldnames], k


@pytest.mark.parametrize("msg_id", MESSAGES)
def test_the_emulators_encoder_packs_what_pymavlink_does(msg_id: int) -> None:
    cls = mavlink2.mavlink_map[msg_id]
    rng = random.Random(-msg_id)
    enc = Encoder(7, compid=1)
    for seq in range(10):
        msg = _random_message(cls, rng)
        assert enc.pack(msg) == _packed(msg, seq, 7, 1), seq


def test_what_is_not_a_clean_unsigned_datagram_is_left_to_pymavlink() -> None:
    mav = mavlink2.MAVLink(None, srcSystem=3, srcComponent=1)
    good = bytes(mav.local_position_ned_encode(5, 1.0, 2.0, -3.0, 0.0, 0.0, 0.0).pack(mav))
    bad_crc = good[:-1] + bytes((good[-1] ^ 0x01,))
    signed = good[:2] + b"\x01" + good[3:]
    unknown = bytearray(good)
    unknown[7:10] = (0xFF, 0xFF, 0xFF)
    for data in (
        bad_crc,
        good + bad_crc,
        good[:-1],
        good + good[:5],
        signed,
        bytes(unknown),
        b"\xfe" + good[1:],
        b"\x00" + good,
    ):
        assert wire.split(data) is None, data.hex()
    assert wire.split(b"") == []
    # A payload whose trailing zeros were cut reads back zero-extended, as pymavlink's decoder.
    zeros = bytes(mav.local_position_ned_encode(0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0).pack(mav))
    assert len(zeros) == wire.OVERHEAD + 1
    unpacker = mavlink2.MAVLink_local_position_ned_message.unpacker
    assert wire.unpack(unpacker, zeros, len(zeros) - 2) == (0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
