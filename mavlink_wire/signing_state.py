"""MAVLink 2 message signing of one system (https://mavlink.io/en/guide/message_signing.html).

A signed frame has incompat flag 0x01 and 13 more bytes after the CRC: link id (1 byte),
timestamp (6 bytes, little-endian, 10 us units since 2015-01-01 UTC) and the first 6 bytes of
SHA-256(secret + header + payload + CRC + link id + timestamp).

Receiving, a frame is accepted only with a correct signature and a timestamp above the last one
accepted on its stream (link id, system, component); the first frame of a stream may be at most
one minute behind our own timestamp. The stream's timestamp moves only after the signature was
found correct, so a forged frame cannot push a stream's timestamp ahead and lock its sender out.
"""

from __future__ import annotations

import hashlib
import hmac
import time
from collections.abc import Callable
from enum import Enum

from mavlink_wire.crc import frame_crc

SECRET_BYTES = 32
SIGNATURE_BYTES = 13
EPOCH_2015 = 1420070400
"""Unix time of 2015-01-01 00:00:00 UTC, the signing timestamps' origin."""
TICKS_PER_SECOND = 100_000
NEW_STREAM_WINDOW = 60 * TICKS_PER_SECOND
"""How far behind our timestamp the first frame of a new stream may be (one minute)."""
_MAGIC_V2, _FLAG_SIGNED, _MIN_FRAME = 0xFD, 0x01, 12


class Verdict(Enum):
    """What :meth:`SigningState.check` found."""

    OK = "ok"
    UNSIGNED = "unsigned"
    """No signature: MAVLink 1, or MAVLink 2 without the signed flag."""
    BAD_SIGNATURE = "bad_signature"
    """Signed with another key, or altered on the way."""
    REPLAY = "replay"
    """Correctly signed, but its timestamp is not newer than the last accepted one."""


class SigningState:
    """Secret, link id, own timestamp and the last timestamp of every stream heard."""

    def __init__(
        self, secret: bytes, link_id: int = 0, clock: Callable[[], float] = time.time
    ) -> None:
        if len(secret) != SECRET_BYTES:
            raise ValueError(f"signing secret of {len(secret)} bytes; need {SECRET_BYTES}")
        if not 0 <= link_id <= 255:
            raise ValueError(f"signing link id {link_id} out of range 0..255")
        self.secret = secret
        self.link_id = link_id
        self._clock = clock
        self.timestamp = self._wall()
        self._streams: dict[tuple[int, int, int], int] = {}

    def _wall(self) -> int:
        return int((max(self._clock(), EPOCH_2015) - EPOCH_2015) * TICKS_PER_SECOND)

    # ----- sending
    def signature(self, frame: bytes) -> bytes:
        """The 13-byte block to append to ``frame``, a MAVLink 2 frame with the signed flag set
        (header, payload, CRC). Each call uses a new timestamp, never behind the wall clock."""
        self.timestamp = max(self.timestamp + 1, self._wall())
        tail = bytes((self.link_id,)) + self.timestamp.to_bytes(6, "little")
        return tail + hashlib.sha256(self.secret + frame + tail).digest()[:6]

    def sign_frame(self, frame: bytes, crc_extra: int) -> bytes:
        """An unsigned MAVLink 2 frame, signed: flag set, CRC recomputed, signature appended."""
        head = bytearray(frame[:-2])
        head[2] |= _FLAG_SIGNED
        head += bytes((crc_extra,))
        crc = frame_crc(bytes(head[1:]))
        signed = bytes(head[:-1]) + crc.to_bytes(2, "little")
        return signed + self.signature(signed)

    # ----- receiving
    def check(self, frame: bytes | bytearray) -> Verdict:
        """Whether one complete received frame may be acted on (updates the stream's state)."""
        if (
            len(frame) < _MIN_FRAME + SIGNATURE_BYTES
            or frame[0] != _MAGIC_V2
            or not frame[2] & _FLAG_SIGNED
        ):
            return Verdict.UNSIGNED
        expected = hashlib.sha256(self.secret + bytes(frame[:-6])).digest()[:6]
        if not hmac.compare_digest(expected, bytes(frame[-6:])):
            return Verdict.BAD_SIGNATURE
        stamp = int.from_bytes(frame[-12:-6], "little")
        stream = (frame[-13], frame[5], frame[6])  # link id, system, component
        last = self._streams.get(stream)
        if last is not None:
            if stamp <= last:
                return Verdict.REPLAY
        elif stamp + NEW_STREAM_WINDOW < max(self.timestamp, self._wall()):
            return Verdict.REPLAY
        self._streams[stream] = stamp
        self.timestamp = max(self.timestamp, stamp)
        return Verdict.OK
