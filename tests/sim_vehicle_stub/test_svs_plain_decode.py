"""The emulator's own decoder of scalar-only messages gives what pymavlink's decoder gives, for
every such message of the dialect, unsigned and signed, with trailing zeros cut; broken frames
are counted as with pymavlink's decoder and the next frame is still decoded."""

from __future__ import annotations

import random
import struct
from typing import Any

import pytest

from sim_vehicle_stub import framing
from sim_vehicle_stub.framing import FrameDecoder, LinkStats
from sim_vehicle_stub.mavlink import dialect
from sim_vehicle_stub.plain_decode import decode_plain, plain_type

PLAIN = sorted(k for k in dialect.mavlink_map if plain_type(k) is not None)

_INT_RANGE = {"B": 8, "H": 16, "I": 32, "Q": 64}


def _value(code: str, rng: random.Random) -> Any:
    if code in "fd":
        if rng.random() < 0.2:
            return 0.0
        return struct.unpack("<f", struct.pack("<f", rng.uniform(-1e6, 1e6)))[0]
    if rng.random() < 0.2:
        return 0
    bits = _INT_RANGE[code.upper()]
    if code.isupper():
        return rng.randrange(0, 2**bits)
    return rng.randrange(-(2 ** (bits - 1)), 2 ** (bits - 1))


def _random_message(cls: Any, rng: random.Random, zeros: bool) -> Any:
    codes = cls.unpacker.format.lstrip("<")
    wire = dict(zip(cls.ordered_fieldnames, codes, strict=True))
    return cls(*[0 if zeros else _value(wire[name], rng) for name in cls.fieldnames])


def _frames(msg: Any, rng: random.Random, signed: bool) -> bytes:
    mav = dialect.MAVLink(None, srcSystem=rng.randrange(1, 256), srcComponent=rng.randrange(256))
    mav.seq = rng.randrange(256)
    if signed:
        mav.signing.secret_key = bytes(range(32))
        mav.signing.sign_outgoing = True
        mav.signing.link_id = 3
        mav.signing.timestamp = 1_000_000
    return bytes(msg.pack(mav))


def _same(fast: Any, slow: Any) -> None:
    assert type(fast) is type(slow)
    mine, theirs = dict(vars(fast)), dict(vars(slow))
    assert vars(mine.pop("_header")) == vars(theirs.pop("_header"))
    assert mine == theirs


def test_the_dialect_has_plain_messages_and_arrays_are_left_to_pymavlink() -> None:
    assert len(PLAIN) > 100
    assert dialect.MAVLINK_MSG_ID_SET_POSITION_TARGET_LOCAL_NED in PLAIN
    assert dialect.MAVLINK_MSG_ID_COMMAND_LONG in PLAIN
    # char[] and arrays: pymavlink's decoder
    assert plain_type(dialect.MAVLINK_MSG_ID_STATUSTEXT) is None
    assert plain_type(dialect.MAVLINK_MSG_ID_PARAM_SET) is None
    assert plain_type(dialect.MAVLINK_MSG_ID_SET_ATTITUDE_TARGET) is None
    assert plain_type(10**6) is None


@pytest.mark.parametrize("signed", [False, True], ids=["unsigned", "signed"])
def test_every_plain_message_decodes_as_pymavlink_decodes_it(signed: bool) -> None:
    rng = random.Random(7)
    mav = dialect.MAVLink(None)
    for msg_id in PLAIN:
        cls = dialect.mavlink_map[msg_id]
        kind = plain_type(msg_id)
        assert kind is not None
        for zeros in (False, False, True):
            frame = _frames(_random_message(cls, rng, zeros), rng, signed)
            _same(decode_plain(kind, frame), mav.decode(bytearray(frame)))


def test_a_broken_frame_is_counted_as_pymavlink_counts_it_and_the_next_is_read(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    rng = random.Random(3)
    cls = dialect.MAVLink_set_position_target_local_ned_message
    good = _frames(_random_message(cls, rng, False), rng, False)
    data = b""
    for flip in (-1, 20, 3):  # the CRC, a payload byte, the sequence number
        broken = bytearray(_frames(_random_message(cls, rng, False), rng, False))
        broken[flip] ^= 0x55
        data += bytes(broken)
    data += good
    fast = LinkStats()
    msgs = FrameDecoder(fast).feed(data)
    monkeypatch.setattr(framing, "plain_type", lambda msg_id: None)
    slow = LinkStats()
    expected = FrameDecoder(slow).feed(data)
    assert fast.bad_crc >= 3
    assert fast == slow
    assert len(msgs) == len(expected) >= 1
    for mine, theirs in zip(msgs, expected, strict=True):
        _same(mine, theirs)
    _same(msgs[-1], dialect.MAVLink(None).decode(bytearray(good)))
