"""The durable mission log of one vehicle: append-only JSON lines, flushed to disk per event.

Every record has ``t`` (mission time, vehicle seconds), ``event`` and its fields. Decisions
(levels, detections, confirmations, phases, the end) are fsync'ed; periodic ``tick`` records
are only flushed. A restarted companion, the fleet's scoring and progress and the run map read
the durable events back typed with :func:`read_log`; :func:`read_records` gives the raw records
of the other events (``tick``, ``stray`` ...).
"""

from __future__ import annotations

import json
import logging
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol, TextIO, TypeVar

from companion.telemetry.events import (
    DURABLE,
    Confirmation,
    DurableEvent,
    End,
    LogFormatError,
    PhaseChange,
    Start,
    from_record,
)

log = logging.getLogger(__name__)

DURABLE_EVENTS = frozenset(DURABLE)
E = TypeVar("E", bound=DurableEvent)


class EventSink(Protocol):
    """Where mission events go: the durable log here; an MQTT publisher later."""

    def emit(self, t: float, event: str, **fields: Any) -> None: ...


class MissionLog:
    """Append-only JSON-lines file; ``emit`` never raises on a full disk: it logs the first
    failure, counts the records lost while writes fail, and says so once they succeed again."""

    def __init__(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        self.path = path
        self._file: TextIO = path.open("a", encoding="utf-8")
        self.lost = 0
        """Records not written since the last write that succeeded."""

    def emit(self, t: float, event: str, **fields: Any) -> None:
        record = {"t": round(t, 3), "event": event, **fields}
        try:
            self._file.write(json.dumps(record, separators=(",", ":")) + "\n")
            self._file.flush()
            if event in DURABLE_EVENTS:
                os.fsync(self._file.fileno())
        except OSError as exc:
            if not self.lost:
                log.error(
                    "mission log %s: %s; records are lost until it can be written", self.path, exc
                )
            self.lost += 1
            return
        if self.lost:
            log.warning("mission log %s written again; %d record(s) lost", self.path, self.lost)
            self.lost = 0

    def close(self) -> None:
        if not self._file.closed:
            try:
                self._file.close()
            except OSError as exc:  # what was still buffered could not be written either
                log.error("mission log %s: %s", self.path, exc)


@dataclass(frozen=True)
class Logged:
    """A durable event and the mission time (vehicle s) it was logged at."""

    t: float
    event: DurableEvent


@dataclass
class Recovered:
    """What a log holds: what a restarted companion takes back, and every durable event."""

    confirmed: list[tuple[float, float]] = field(default_factory=list)
    last_time: float = 0.0
    """The latest mission time of any record (``tick`` included)."""
    ended: bool = False
    starts: int = 0
    search_start: float | None = None
    """The first search start logged (a resumed search keeps it)."""
    events: list[Logged] = field(default_factory=list)
    """The durable events in log order."""

    def of(self, kind: type[E]) -> list[E]:
        """The events of one kind, in log order."""
        return [e.event for e in self.events if isinstance(e.event, kind)]

    def end(self) -> End | None:
        """The last end logged, if any."""
        ends = self.of(End)
        return ends[-1] if ends else None


def read_log(path: Path) -> Recovered:
    """The durable events, the last mission time and what follows from them; skips torn lines.

    Raises :class:`LogFormatError` (path, line and field) for a durable record that does not
    match its event class: a log written by another version is refused, not half-recovered.
    """
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
            t = record.get("t", 0.0)
            if isinstance(t, bool) or not isinstance(t, int | float):
                raise LogFormatError(f"{path}:{number}: field 't' is {t!r}, not a number")
            out.last_time = max(out.last_time, float(t))
            event = from_record(record, f"{path}:{number}")
            if event is None:
                continue
            out.events.append(Logged(float(t), event))
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
    """Every readable record of a log, as raw dicts: for the events that are not durable
    (durable ones are read typed through :func:`read_log`)."""
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
