"""The durable mission log of one vehicle: append-only JSON lines, flushed to disk per event.

Every record has ``t`` (mission time, vehicle seconds), ``event`` and its fields. Decisions
(levels, detections, confirmations, phases, the end) are fsync'ed; periodic ``tick`` records
are only flushed. A restarted companion reads it back with :func:`read_log`.
"""

from __future__ import annotations

import json
import logging
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol, TextIO

from companion.telemetry.events import DURABLE, Confirmation, End, PhaseChange, Start, from_record

log = logging.getLogger(__name__)

DURABLE_EVENTS = frozenset(DURABLE)


class EventSink(Protocol):
    """Where mission events go: the durable log here; an MQTT publisher later."""

    def emit(self, t: float, event: str, **fields: Any) -> None: ...


class MissionLog:
    """Append-only JSON-lines file; ``emit`` never raises on a full disk, it logs the error."""

    def __init__(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        self.path = path
        self._file: TextIO = path.open("a", encoding="utf-8")

    def emit(self, t: float, event: str, **fields: Any) -> None:
        record = {"t": round(t, 3), "event": event, **fields}
        try:
            self._file.write(json.dumps(record, separators=(",", ":")) + "\n")
            self._file.flush()
            if event in DURABLE_EVENTS:
                os.fsync(self._file.fileno())
        except OSError as exc:
            log.error("mission log %s: %s", self.path, exc)

    def close(self) -> None:
        if not self._file.closed:
            self._file.close()


@dataclass
class Recovered:
    """What a restarted companion takes back from its log."""

    confirmed: list[tuple[float, float]] = field(default_factory=list)
    last_time: float = 0.0
    ended: bool = False
    starts: int = 0
    search_start: float | None = None


def read_log(path: Path) -> Recovered:
    """Confirmed positions, last mission time and whether the mission ended; skips torn lines."""
    out = Recovered()
    if not path.exists():
        return out
    with path.open(encoding="utf-8") as f:
        for number, line in enumerate(f, start=1):
            try:
                record = json.loads(line)
            except json.JSONDecodeError:
                log.warning("%s:%d: unreadable record skipped", path, number)
                continue
            if not isinstance(record, dict):
                continue
            out.last_time = max(out.last_time, float(record.get("t", 0.0)))
            event = from_record(record)
            if isinstance(event, Confirmation):
                out.confirmed.append((float(event.north), float(event.east)))
            elif isinstance(event, End):
                out.ended = True
            elif isinstance(event, Start):
                out.starts += 1
            elif (
                isinstance(event, PhaseChange)
                and event.search_start is not None
                and out.search_start is None
            ):
                out.search_start = float(event.search_start)
    return out


def read_records(path: Path) -> list[dict[str, Any]]:
    """Every readable record of a log (for scoring and progress)."""
    records: list[dict[str, Any]] = []
    if not path.exists():
        return records
    with path.open(encoding="utf-8") as f:
        for line in f:
            try:
                record = json.loads(line)
            except json.JSONDecodeError:
                continue
            if isinstance(record, dict):
                records.append(record)
    return records
