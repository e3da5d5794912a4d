"""The durable mission-log events as frozen dataclasses: one definition used by the writer
(``VehicleMission.record``) and by :func:`companion.telemetry.mission_log.read_log`, so a
renamed field fails loudly in both instead of silently breaking restart recovery.

A record is ``{"t": ..., "event": NAME, **fields}``; optional fields that are None are left out
(the log's shape before these classes existed, which other readers still parse as dicts).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from typing import Any, ClassVar


@dataclass(frozen=True)
class Start:
    NAME: ClassVar[str] = "start"
    vehicle: int
    profile: str
    seed: int
    resumed: int
    """Confirmed targets read back from the log."""
    altitude: float


@dataclass(frozen=True)
class PhaseChange:
    NAME: ClassVar[str] = "phase"
    phase: str
    search_start: float | None = None
    """Mission time the search began (on entering the search)."""
    by: str | None = None
    """``operator`` for an operator's pause."""


@dataclass(frozen=True)
class Level:
    NAME: ClassVar[str] = "level"
    level: int
    sensor: int


@dataclass(frozen=True)
class Detection:
    NAME: ClassVar[str] = "detection"
    north: float
    east: float
    level: int


@dataclass(frozen=True)
class Confirmation:
    NAME: ClassVar[str] = "confirmation"
    north: float
    east: float
    level: int
    found: int


@dataclass(frozen=True)
class Fallback:
    NAME: ClassVar[str] = "fallback"
    level: int


@dataclass(frozen=True)
class ModeChange:
    NAME: ClassVar[str] = "mode"
    mode: str
    guided: bool


@dataclass(frozen=True)
class LinkState:
    NAME: ClassVar[str] = "link"
    state: str
    """``lost`` or ``restored``."""
    silent: float | None = None


@dataclass(frozen=True)
class End:
    NAME: ClassVar[str] = "end"
    reason: str
    found: int


DurableEvent = (
    Start | PhaseChange | Level | Detection | Confirmation | Fallback | ModeChange | LinkState | End
)
DURABLE: dict[str, type[DurableEvent]] = {
    cls.NAME: cls
    for cls in (Start, PhaseChange, Level, Detection, Confirmation, Fallback, ModeChange,
                LinkState, End)
}  # fmt: skip
"""Event name -> class; these records are fsync'ed."""


def to_fields(event: DurableEvent) -> dict[str, Any]:
    """The record's fields (None-valued optional fields left out)."""
    return {k: v for k, v in asdict(event).items() if v is not None}


def from_record(record: dict[str, Any]) -> DurableEvent | None:
    """The durable event a record holds; None for other events and for a record that lacks a
    required field (a torn or foreign line)."""
    cls = DURABLE.get(str(record.get("event")))
    if cls is None:
        return None
    known = {f.name for f in fields(cls)}
    try:
        return cls(**{k: v for k, v in record.items() if k in known})
    except TypeError:
        return None
