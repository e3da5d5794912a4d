"""The autopilot's own log of the flight, downloaded over MAVLink's log protocol
(LOG_REQUEST_LIST -> LOG_ENTRY, LOG_REQUEST_DATA -> LOG_DATA, LOG_REQUEST_END): ArduPilot's
dataflash ``.bin`` (GCS_MAVLink/GCS_Logs.cpp in AP_Logger), PX4's ``.ulg``
(src/modules/mavlink/mavlink_log_handler.cpp). The newest log is the flight just flown; the
whole file is asked for at once and the gaps the link dropped are asked for again."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

LOG_KINDS = frozenset({"LOG_ENTRY", "LOG_DATA"})
"""Messages of the log protocol the transfer reads."""

FLIGHT_LOG_WAIT_S = 300.0
"""Wall seconds a companion spends downloading the log once landed, by default."""

MAGIC = {b"\xa3\x95": ".bin", b"ULog\x01\x12\x35": ".ulg"}
"""The first bytes of an ArduPilot dataflash log and of a PX4 ULog, and the file's suffix."""


@dataclass(frozen=True)
class FlightLog:
    """Where the autopilot's log was kept, or why it was not."""

    path: Path | None
    size: int = 0
    note: str = ""
    """Why there is no log, or what is wrong with the one kept (a partial download)."""

    def describe(self) -> str:
        if self.path is None:
            return f"no autopilot log: {self.note}"
        more = f" ({self.note})" if self.note else ""
        return f"autopilot log {self.path} ({self.size} bytes){more}"


def suffix(head: bytes) -> str:
    """``.bin``, ``.ulg`` or ``.log`` (not a format known here) from a log's first bytes."""
    return next((s for magic, s in MAGIC.items() if head.startswith(magic)), ".log")


class LogTransfer:
    """One download at a time over ``send`` (encoded messages out) and ``inbox`` (the link puts
    every LOG_ENTRY and LOG_DATA of the vehicle there)."""

    def __init__(
        self,
        mav: Any,
        send: Callable[[Any], None],
        target_system: int,
        *,
        answer: float = 3.0,
        tries: int = 3,
    ) -> None:
        self._mav = mav
        self._send = send
        self._target = target_system
        self._answer = answer
        """Wall seconds to wait for the list's first answer, and for data once asked."""
        self._tries = tries
        """Requests in a row that may go unanswered before the download stops."""
        self.inbox: asyncio.Queue[Any] = asyncio.Queue()

    async def download(self, stem: Path, limit: float) -> FlightLog:
        """The newest log into ``stem`` + its format's suffix, within ``limit`` wall s and
        while the vehicle answers (what came by then is kept and named partial)."""
        entry = await self._newest()
        if isinstance(entry, str):
            return FlightLog(None, note=entry)
        log_id, size = entry
        data = bytearray(size)
        missing = [(0, size)]
        deadline = time.monotonic() + limit
        silent = 0
        try:
            while missing and time.monotonic() < deadline and silent < self._tries:
                ofs, count = missing[0]
                self._send(self._mav.log_request_data_encode(self._target, 1, log_id, ofs, count))
                got = await self._receive(log_id, data, missing, (ofs, ofs + count), deadline)
                silent = 0 if got else silent + 1
        finally:
            self._send(self._mav.log_request_end_encode(self._target, 1))
        kept = missing[0][0] if missing else size  # the log up to its first gap
        if kept == 0:
            return FlightLog(None, note=f"log {log_id} ({size} bytes): no data within {limit:g} s")
        path = stem.with_suffix(suffix(bytes(data[:8])))
        path.write_bytes(bytes(data[:kept]))
        if missing:
            note = f"partial: the first {kept} of {size} bytes"
            return FlightLog(path, kept, note)
        return FlightLog(path, size)

    async def _newest(self) -> tuple[int, int] | str:
        """(id, size) of the newest log, or why there is none."""
        self._drain()
        self._send(self._mav.log_request_list_encode(self._target, 1, 0, 0xFFFF))
        entries: dict[int, int] = {}
        total: int | None = None
        wait = self._answer
        while total is None or len(entries) < total:
            try:
                msg = await asyncio.wait_for(self._next("LOG_ENTRY"), wait)
            except TimeoutError:
                break
            total, wait = msg.num_logs, 1.0
            if msg.num_logs > 0:
                entries[msg.id] = msg.size
        if total is None:
            return f"the vehicle did not answer LOG_REQUEST_LIST in {self._answer:g} s"
        if not entries:
            return "the vehicle holds no log"
        newest = max(entries)
        if entries[newest] == 0:
            return f"the vehicle's newest log ({newest}) is empty"
        return newest, entries[newest]

    async def _receive(
        self,
        log_id: int,
        data: bytearray,
        missing: list[tuple[int, int]],
        asked: tuple[int, int],
        deadline: float,
    ) -> bool:
        """LOG_DATA into ``data`` until nothing of the range ``asked`` is missing or the
        vehicle goes quiet; ``missing`` is updated. False when nothing came at all."""
        got = False
        while _overlaps(missing, *asked):
            left = min(self._answer, deadline - time.monotonic())
            if left <= 0:
                return got
            try:
                msg = await asyncio.wait_for(self._next("LOG_DATA"), left)
            except TimeoutError:
                return got
            if msg.id != log_id or msg.count == 0:
                continue
            got = True
            end = min(msg.ofs + msg.count, len(data))
            data[msg.ofs : end] = bytes(msg.data[: end - msg.ofs])
            _take(missing, msg.ofs, end)
        return got

    async def _next(self, kind: str) -> Any:
        while True:
            msg = await self.inbox.get()
            if msg.get_type() == kind:
                return msg

    def _drain(self) -> None:
        while not self.inbox.empty():
            self.inbox.get_nowait()


def _overlaps(missing: list[tuple[int, int]], start: int, end: int) -> bool:
    """Whether any of [start, end) is still in ``missing``."""
    return any(ofs < end and start < ofs + count for ofs, count in missing)


def _take(missing: list[tuple[int, int]], start: int, end: int) -> None:
    """Remove [start, end) from the (offset, count) ranges ``missing``."""
    kept: list[tuple[int, int]] = []
    for ofs, count in missing:
        stop = ofs + count
        if end <= ofs or start >= stop:
            kept.append((ofs, count))
            continue
        if ofs < start:
            kept.append((ofs, start - ofs))
        if end < stop:
            kept.append((end, stop - end))
    missing[:] = kept
