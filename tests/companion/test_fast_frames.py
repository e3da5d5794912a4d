"""The pymavlink link's fast path for the per-tick messages gives pymavlink's events and log."""

from __future__ import annotations

import asyncio
import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.link.messages import LinkEvent, LocalPosition
from companion.link.pymavlink_link import PymavlinkLink
from mavlink_wire import frames as wire


def _datagrams(*, truncate: bool = False) -> list[bytes]:
    rng = np.random.default_rng(7)
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    other = mavlink2.MAVLink(None, srcSystem=2, srcComponent=1)
    v1 = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    v1.WIRE_PROTOCOL_VERSION = "1.0"

    def pack(m: Any, msg: Any) -> bytes:
        return bytes(msg.pack(m))

    out = []
    for k in range(300):
        x, y = (float(v) for v in rng.normal(0, 5000, 2))
        frames = [
            pack(mav, mav.local_position_ned_encode(100 * k, x, y, -30.0, 20.0, 0.0, 0.0)),
            pack(mav, mav.named_value_float_encode(100 * k, b"SENS_SIG", float(rng.random()))),
        ]
        if k % 3 == 0:
            frames.append(pack(mav, mav.debug_vect_encode(b"DET", 10**5 * k, x, y, 0.4)))
            frames.append(pack(mav, mav.debug_vect_encode(b"CNF", 10**5 * k, 0.0, 0.0, 0.0)))
            frames.append(pack(mav, mav.debug_vect_encode(b"XYZ", 10**5 * k, x, y, 0.4)))
        if k % 5 == 0:
            frames.insert(0, pack(mav, mav.heartbeat_encode(2, 12, 217, 393216, 4, 3)))
            frames.append(
                pack(mav, mav.sys_status_encode(1, 1, 1, 100, 1, 500, 9, 0, 0, 0, 0, 0, 0))
            )
            frames.append(pack(mav, mav.named_value_float_encode(0, b"OTHER", 1.0)))
            frames.append(pack(mav, mav.command_ack_encode(511, 0)))
        if k % 7 == 0:
            frames.append(pack(other, other.local_position_ned_encode(1, 1.0, 2.0, 3.0, 0, 0, 0)))
        if k % 11 == 0:  # broken: bad CRC
            bad = bytearray(frames[0])
            bad[-1] ^= 0xFF
            frames[0] = bytes(bad)
        if k % 13 == 0:
            frames.append(pack(v1, v1.local_position_ned_encode(5, 9.0, 9.0, 9.0, 0, 0, 0)))
        if k % 17 == 0:
            frames.append(b"\x00garbage")
        if truncate and k % 19 == 0:
            frames[-1] = frames[-1][:-3]  # truncated
        out.append(b"".join(frames))
    return out


def _run(tmp: Path, data: list[bytes], *, fast: bool) -> tuple[list[LinkEvent], bytes, int]:
    async def main() -> tuple[list[LinkEvent], bytes, int]:
        link = PymavlinkLink(url="udpin:127.0.0.1:1", target_system=1, tlog=tmp / "v.tlog")
        link._tlog = __import__("companion.link.tlog", fromlist=["T"]).TelemetryLog(tmp / "v.tlog")
        for d in data:
            link._receive(d, ("127.0.0.1", 5) if fast else None)
            link._publish_pending()
        events = []
        while not link.events.empty():
            events.append(link.events.get_nowait())
        await link.close()
        return events, (tmp / "v.tlog").read_bytes(), link.bad_packets

    return asyncio.run(main())


def _strip(events: list[LinkEvent]) -> list[Any]:
    return [
        dataclasses.replace(e, received=0.0) if isinstance(e, LocalPosition) else e for e in events
    ]


def _messages(tlog: bytes) -> list[bytes]:
    """The logged frames without their wall-clock stamps."""
    mav = mavlink2.MAVLink(None)
    out, i = [], 0
    while i < len(tlog):
        i += 8
        n = 12 + tlog[i + 1] if tlog[i] == 0xFD else 8 + tlog[i + 1]
        out.append(tlog[i : i + n])
        assert mav.parse_buffer(tlog[i : i + n])
        i += n
    return out


def test_fast_path_events_and_log_equal_pymavlink(tmp_path: Path) -> None:
    data = _datagrams()
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    slow = _run(tmp_path / "a", data, fast=False)  # addr None: the pymavlink path throughout
    fast = _run(tmp_path / "b", data, fast=True)
    assert len(slow[0]) > 600
    assert _strip(fast[0]) == _strip(slow[0])
    assert _messages(fast[1]) == _messages(slow[1])
    assert fast[2] == slow[2] > 0


def test_split_leaves_anything_unusual_to_pymavlink() -> None:
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    good = bytes(mav.local_position_ned_encode(1, 1.0, 2.0, 3.0, 0, 0, 0).pack(mav))
    assert wire.split(good) == [(32, 1, good)]
    assert wire.split(good + good[:-1]) is None
    assert wire.split(good[:-1] + b"\x00") is None
    assert wire.split(b"\xfe" + good[1:]) is None


def test_a_truncated_datagram_no_longer_swallows_the_next_position(tmp_path: Path) -> None:
    """pymavlink keeps a cut frame's bytes for the next read (right for TCP, not for UDP): the
    whole-datagram path then loses the first frame of the next datagram; the fast path reads a
    well-formed datagram on its own."""
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    cut = bytes(mav.local_position_ned_encode(100, 1.0, 1.0, -30.0, 0, 0, 0).pack(mav))[:-3]
    nxt = bytes(mav.local_position_ned_encode(200, 2.0, 2.0, -30.0, 0, 0, 0).pack(mav))
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    slow = _run(tmp_path / "a", [cut, nxt], fast=False)[0]
    fast = _run(tmp_path / "b", [cut, nxt], fast=True)[0]
    assert [e.north for e in fast if isinstance(e, LocalPosition)] == [2.0]
    assert [e.north for e in slow if isinstance(e, LocalPosition)] == []
