"""The durable event outbox of one vehicle: every event gets a sequence number and is on disk
before it is sent, so a broker outage or a companion restart loses none.

Two append-only files beside the mission log: ``mqtt-outbox-I.jsonl`` (one event payload a
line, exactly as published, with ``seq``) and ``mqtt-outbox-I.acked`` (after each delivered
batch, the highest ``seq`` the broker acknowledged, everything before it delivered too). A
restarted companion continues the numbering and sends what was not acknowledged, in order.
"""

from __future__ import annotations

import asyncio
import json
import logging
import os
from collections import deque
from pathlib import Path
from typing import Any, TextIO

from companion.telemetry.mission_log import DURABLE_EVENTS

log = logging.getLogger(__name__)


class EventOutbox:
    """Events waiting for the broker's acknowledgement, oldest first; ``append`` never raises."""

    def __init__(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        self.path = path
        self.acked_path = path.with_suffix(".acked")
        self.acked = _last_acked(self.acked_path)
        self._pending: deque[tuple[int, bytes]] = deque()
        self.next_seq = self._load()
        self._file: TextIO = _open_append(path)
        self._acked_file: TextIO = _open_append(self.acked_path)
        self.ready = asyncio.Event()
        if self._pending:
            self.ready.set()

    def append(self, record: dict[str, Any]) -> int:
        """Number ``record`` (adds ``seq`` first), write it, queue it; returns its ``seq``."""
        seq = self.next_seq
        self.next_seq += 1
        line = json.dumps({"seq": seq, **record}, separators=(",", ":"), default=str)
        self._pending.append((seq, line.encode()))
        self.ready.set()
        try:
            self._file.write(line + "\n")
            self._file.flush()
            if record.get("event") in DURABLE_EVENTS:
                os.fsync(self._file.fileno())
        except OSError as exc:
            log.error("MQTT outbox %s: %s (event %d kept in memory only)", self.path, exc, seq)
        return seq

    def pending(self, limit: int) -> list[tuple[int, bytes]]:
        """Up to ``limit`` oldest unacknowledged (seq, payload)."""
        return [self._pending[i] for i in range(min(limit, len(self._pending)))]

    def __len__(self) -> int:
        return len(self._pending)

    def ack(self, seq: int) -> None:
        """The broker has every event up to ``seq``."""
        while self._pending and self._pending[0][0] <= seq:
            self._pending.popleft()
        if not self._pending:
            self.ready.clear()
        self.acked = max(self.acked, seq)
        try:
            self._acked_file.write(f"{seq}\n")
            self._acked_file.flush()
        except OSError as exc:
            log.error("MQTT outbox %s: %s", self.acked_path, exc)

    def close(self) -> None:
        for f in (self._file, self._acked_file):
            if not f.closed:
                f.close()

    def _load(self) -> int:
        """Queue the unacknowledged events of an earlier run; the next free ``seq``."""
        next_seq = self.acked + 1
        if not self.path.exists():
            return next_seq
        with self.path.open(encoding="utf-8") as f:
            for number, line in enumerate(f, start=1):
                try:
                    seq = int(json.loads(line)["seq"])
                except (ValueError, KeyError, TypeError):
                    log.warning("%s:%d: unreadable event skipped", self.path, number)
                    continue
                next_seq = max(next_seq, seq + 1)
                if seq > self.acked:
                    self._pending.append((seq, line.rstrip("\n").encode()))
        return next_seq


def _last_acked(path: Path) -> int:
    if not path.exists():
        return -1
    last = -1
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.strip().isdigit():
            last = max(last, int(line))
    return last


def _open_append(path: Path) -> TextIO:
    """Open for appending, first ending a line torn by a crash so the next record stays whole."""
    torn = False
    if path.exists() and path.stat().st_size > 0:
        with path.open("rb") as existing:
            existing.seek(-1, os.SEEK_END)
            torn = existing.read(1) != b"\n"
    f = path.open("a", encoding="utf-8")
    if torn:
        f.write("\n")
    return f
