"""The log download (companion/link/log_transfer.py) against a vehicle that answers as the log
protocol says, in pymavlink's own messages, and drops some of them: the newest log is asked for,
the gaps are asked for again, a vehicle that does not answer or holds no log is named, and a
download cut short keeps the log up to its first gap, named partial."""

from __future__ import annotations

import asyncio
import os
from pathlib import Path
from typing import Any

import pytest

from companion.link.log_transfer import FlightLog, LogTransfer, suffix

os.environ.setdefault("MAVLINK20", "1")
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

ULOG = b"ULog\x01\x12\x35" + bytes(range(256)) * 40


class _Vehicle:
    """Logs by id; answers LOG_REQUEST_LIST and LOG_REQUEST_DATA into ``transfer.inbox``,
    leaving out the LOG_DATA whose sequence number is in ``drop`` (once each)."""

    def __init__(self, logs: dict[int, bytes], drop: set[int] | None = None, quiet: bool = False):
        self.mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
        self.logs, self.drop, self.quiet = logs, set(drop or ()), quiet
        self.sent = 0
        self.requests: list[tuple[int, int]] = []
        self.transfer = LogTransfer(self.mav, self.receive, 1, answer=0.2)

    def receive(self, msg: Any) -> None:
        kind, inbox = msg.get_type(), self.transfer.inbox
        if self.quiet:
            return
        if kind == "LOG_REQUEST_LIST":
            if not self.logs:
                inbox.put_nowait(self.mav.log_entry_encode(0, 0, 0, 0, 0))
            last = max(self.logs, default=0)
            for i, data in sorted(self.logs.items()):
                inbox.put_nowait(self.mav.log_entry_encode(i, len(self.logs), last, 0, len(data)))
        elif kind == "LOG_REQUEST_DATA":
            self.requests.append((msg.ofs, msg.count))
            data = self.logs[msg.id]
            end = min(msg.ofs + msg.count, len(data))
            for ofs in range(msg.ofs, end, 90):
                self.sent += 1
                if self.sent in self.drop:
                    continue
                chunk = data[ofs : min(ofs + 90, end)]
                padded = list(chunk) + [0] * (90 - len(chunk))
                inbox.put_nowait(self.mav.log_data_encode(msg.id, ofs, len(chunk), padded))


def _download(vehicle: _Vehicle, stem: Path, limit: float = 10.0) -> FlightLog:
    return asyncio.run(vehicle.transfer.download(stem, limit))


def test_the_newest_log_is_downloaded_whole(tmp_path: Path) -> None:
    vehicle = _Vehicle({1: b"\xa3\x95" + b"old" * 100, 2: ULOG})
    kept = _download(vehicle, tmp_path / "autopilot-0")
    assert kept == FlightLog(tmp_path / "autopilot-0.ulg", len(ULOG))
    assert kept.path is not None
    assert kept.path.read_bytes() == ULOG
    assert vehicle.requests == [(0, len(ULOG))]


def test_the_gaps_a_link_dropped_are_asked_for_again(tmp_path: Path) -> None:
    vehicle = _Vehicle({3: ULOG}, drop={2, 40, 41, 115})
    kept = _download(vehicle, tmp_path / "autopilot-0")
    assert kept.path is not None
    assert kept.path.read_bytes() == ULOG
    assert kept.note == ""
    assert vehicle.requests[0] == (0, len(ULOG))
    # the 115th LOG_DATA, the first gap's again, is dropped too: asked for a third time
    assert vehicle.requests[1:] == [(90, 90), (90, 90), (39 * 90, 180)]


def test_a_download_cut_short_keeps_the_log_up_to_its_first_gap(tmp_path: Path) -> None:
    vehicle = _Vehicle({3: ULOG}, drop=set(range(50, 200)))  # never sent again in time
    kept = _download(vehicle, tmp_path / "autopilot-0", limit=0.5)
    assert kept.path == tmp_path / "autopilot-0.ulg"
    assert kept.path.read_bytes() == ULOG[: 49 * 90]
    assert kept.note == f"partial: the first {49 * 90} of {len(ULOG)} bytes"


@pytest.mark.parametrize(
    ("vehicle", "note"),
    [
        (_Vehicle({}, quiet=True), "the vehicle did not answer LOG_REQUEST_LIST in 0.2 s"),
        (_Vehicle({}), "the vehicle holds no log"),
        (_Vehicle({4: b""}), "the vehicle's newest log (4) is empty"),
    ],
)
def test_no_log_says_why(vehicle: _Vehicle, note: str, tmp_path: Path) -> None:
    assert _download(vehicle, tmp_path / "autopilot-0") == FlightLog(None, note=note)
    assert list(tmp_path.iterdir()) == []
    assert FlightLog(None, note=note).describe() == f"no autopilot log: {note}"


def test_the_suffix_follows_the_format() -> None:
    assert suffix(b"\xa3\x95\x80\x80") == ".bin"
    assert suffix(ULOG[:8]) == ".ulg"
    assert suffix(b"\x00\x01") == ".log"
