"""Split received bytes into MAVLink frames, decode them, and count everything that is dropped
(the frame layout is the wire's, :mod:`mavlink_wire.frames`).

Each UDP datagram is parsed on its own (a truncated frame never poisons the next datagram); a
TCP stream keeps at most one partial frame between reads.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from mavlink_wire.frames import HEADER_BYTES, MAGIC, OVERHEAD, msg_id_at
from mavlink_wire.signing_state import SIGNATURE_BYTES
from sim_vehicle_stub.mavlink import dialect
from sim_vehicle_stub.plain_decode import decode_plain, plain_type

_V2, _V1 = MAGIC, 0xFE
_MAX_FRAMES_PER_READ = 64


@dataclass
class LinkStats:
    """Counters of one vehicle's links (all endpoints together)."""

    datagrams: int = 0
    bytes: int = 0
    messages: int = 0
    rejected_datagrams: int = 0
    """Datagrams (or stream reads) in which anything was dropped."""
    bad_crc: int = 0
    truncated: int = 0
    unknown_id: int = 0
    malformed: int = 0
    garbage: int = 0
    """Runs of bytes that do not start a frame."""
    flood_dropped: int = 0
    """Datagrams dropped unread because the sender exceeded the rate limit."""
    not_for_us: int = 0
    nacks: int = 0
    """Commands answered with a failure result."""
    tx_dropped: int = 0
    """Outgoing datagrams dropped because the kernel's send buffer was full."""
    unsigned: int = 0
    """Signing on: messages without a signature (or MAVLink 1), not acted on."""
    bad_signature: int = 0
    """Signing on: messages signed with another key or altered on the way, not acted on."""
    replayed: int = 0
    """Signing on: correctly signed messages with a timestamp already seen (replays)."""

    @property
    def dropped(self) -> int:
        return (
            self.bad_crc
            + self.truncated
            + self.unknown_id
            + self.malformed
            + self.garbage
            + self.flood_dropped
        )

    @property
    def signing_rejected(self) -> int:
        return self.unsigned + self.bad_signature + self.replayed

    def as_dict(self) -> dict[str, int]:
        return {**asdict(self), "dropped": self.dropped, "signing_rejected": self.signing_rejected}


class FrameDecoder:
    """Decoder for one endpoint; ``stream`` keeps partial frames across reads (TCP)."""

    def __init__(self, stats: LinkStats, *, stream: bool = False) -> None:
        self.stats = stats
        self.stream = stream
        self._pending = b""
        self._mav = dialect.MAVLink(None)

    def feed(self, data: bytes) -> list[Any]:
        """Decoded messages in ``data``; every problem is counted and skipped."""
        stats = self.stats
        stats.datagrams += 1
        stats.bytes += len(data)
        buf = self._pending + data if self.stream else data
        self._pending = b""
        out: list[Any] = []
        errors = 0
        resync = False  # bytes skipped after a broken frame belong to that frame, not garbage
        i, n = 0, len(buf)
        while i < n:
            if not self.stream and len(out) >= _MAX_FRAMES_PER_READ:
                stats.flood_dropped += 1
                errors += 1
                break
            magic = buf[i]
            if magic not in (_V1, _V2):
                j1, j2 = buf.find(b"\xfd", i), buf.find(b"\xfe", i)
                nxt = min(j for j in (j1, j2, n) if j >= 0)
                if not resync:
                    stats.garbage += 1
                    errors += 1
                i = nxt
                continue
            head = HEADER_BYTES if magic == _V2 else 6
            if n - i < head:
                total = -1
            else:
                plen = buf[i + 1]
                if magic == _V2:
                    incompat = buf[i + 2]
                    if incompat & ~1:
                        stats.malformed += 1
                        errors += 1
                        resync = True
                        i += 1
                        continue
                    total = OVERHEAD + plen + (SIGNATURE_BYTES if incompat & 1 else 0)
                else:
                    total = 8 + plen
            if total < 0 or n - i < total:
                if self.stream and n - i < 300:
                    self._pending = buf[i:]
                else:
                    stats.truncated += 1
                    errors += 1
                break
            msgid = msg_id_at(buf, i) if magic == _V2 else buf[i + 5]
            if msgid not in dialect.mavlink_map:
                stats.unknown_id += 1
                errors += 1
                i += total
                continue
            plain = plain_type(msgid) if magic == _V2 else None
            try:
                if plain is not None:
                    msg = decode_plain(plain, buf[i : i + total])
                else:
                    msg = self._mav.decode(bytearray(buf[i : i + total]))
            except dialect.MAVError as exc:
                if "CRC" in str(exc):
                    stats.bad_crc += 1
                else:
                    stats.malformed += 1
                errors += 1
                resync = True
                i += 1
                continue
            except Exception:  # pymavlink may raise anything on hostile payloads
                stats.malformed += 1
                errors += 1
                resync = True
                i += 1
                continue
            resync = False
            out.append(msg)
            i += total
        stats.messages += len(out)
        if errors:
            stats.rejected_datagrams += 1
        return out
