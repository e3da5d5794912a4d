"""The durable mission-log events as frozen dataclasses: one definition used by the writer
(``VehicleMission.record``) and by :func:`companion.telemetry.mission_log.read_log`, so a
renamed field fails loudly in both instead of silently breaking restart recovery.

A record is ``{"t": ..., "event": NAME, **fields}``; optional fields that are None are left out
(the log's shape before these classes existed). Every reader (restart recovery, fleet scoring and
progress, the run map) takes them through :func:`from_record`, which refuses a record whose
fields do not match its class with :class:`LogFormatError` naming the file, line and field.
"""

from __future__ import annotations

from dataclasses import MISSING, asdict, dataclass, fields
from typing import Any, ClassVar, get_type_hints

from companion.errors import CompanionError


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


@dataclass(frozen=True)
class TelemetryDropped:
    """Positions the telemetry check dropped (companion/link/telemetry_guard.py), per cause,
    since the last such record (rate-limited)."""

    NAME: ClassVar[str] = "telemetry_dropped"
    cause: str
    count: int
    total: int
    """Dropped for this cause since the start."""


@dataclass(frozen=True)
class SetpointRefused:
    """A setpoint the last check refused (a bug upstream) and replaced by a hold
    (companion/mission/setpoint_guard.py); rate-limited per cause."""

    NAME: ClassVar[str] = "setpoint_refused"
    cause: str
    detail: str
    count: int
    """Refused for this cause since the start."""


@dataclass(frozen=True)
class AltitudeLayer:
    """The vehicle left its altitude layer, or is back in it, during the search
    (companion/mission/layer_watch.py)."""

    NAME: ClassVar[str] = "altitude_layer"
    state: str
    """``outside`` or ``back``."""
    altitude: float
    """m above home, as the vehicle reported it."""
    layer: float
    tolerance: float


@dataclass(frozen=True)
class Exit:
    """How the companion ends: its exit status and the cause in one line."""

    NAME: ClassVar[str] = "exit"
    status: int
    cause: str


DurableEvent = (
    Start | PhaseChange | Level | Detection | Confirmation | Fallback | ModeChange | LinkState | End
    | TelemetryDropped | SetpointRefused | AltitudeLayer | Exit
)  # fmt: skip
DURABLE: dict[str, type[DurableEvent]] = {
    cls.NAME: cls
    for cls in (Start, PhaseChange, Level, Detection, Confirmation, Fallback, ModeChange,
                LinkState, End, TelemetryDropped, SetpointRefused, AltitudeLayer, Exit)
}  # fmt: skip
"""Event name -> class; these records are fsync'ed."""


def to_fields(event: DurableEvent) -> dict[str, Any]:
    """The record's fields (None-valued optional fields left out)."""
    return {k: v for k, v in asdict(event).items() if v is not None}


class LogFormatError(CompanionError, ValueError):
    """A durable record that does not match its event class (a log written by another version:
    a field renamed, missing, added or of another type)."""


_JSON_TYPES: dict[type, tuple[type, ...]] = {float: (float, int), int: (int,), str: (str,),
                                             bool: (bool,)}  # fmt: skip
"""What JSON may hold for a field of each type (a float written as 1.0 may read back as 1)."""


def _field_types(cls: type[DurableEvent]) -> dict[str, tuple[tuple[type, ...], bool]]:
    """Per field: the JSON types it accepts and whether it is required."""
    hints = get_type_hints(cls)
    out: dict[str, tuple[tuple[type, ...], bool]] = {}
    for f in fields(cls):
        kinds = getattr(hints[f.name], "__args__", (hints[f.name],))
        accepted = tuple(t for k in kinds if k is not type(None) for t in _JSON_TYPES[k])
        out[f.name] = (accepted, f.default is MISSING)
    return out


_FIELDS = {name: _field_types(cls) for name, cls in DURABLE.items()}


def from_record(record: dict[str, Any], where: str = "record") -> DurableEvent | None:
    """The durable event a record holds; None for an event that is not durable (``tick`` ...).

    ``where`` (``path:line``) starts the error message. Raises :class:`LogFormatError` when a
    durable record lacks a required field, has one its class does not know or one of the
    wrong type: a log of another version, which must not be half-read into a recovery.
    """
    name = str(record.get("event"))
    cls = DURABLE.get(name)
    if cls is None:
        return None
    known = _FIELDS[name]
    values = {k: v for k, v in record.items() if k not in ("t", "event")}
    for key, value in values.items():
        if key not in known:
            raise LogFormatError(
                f"{where}: {name!r} record has field {key!r}, which {cls.__name__} does not "
                f"know (its fields: {', '.join(known)})"
            )
        accepted = known[key][0]
        # JSON's true is a Python int too: only a bool field takes it
        if not isinstance(value, accepted) or (isinstance(value, bool) and bool not in accepted):
            raise LogFormatError(
                f"{where}: {name!r} record field {key!r} is {value!r}, not "
                f"{' or '.join(t.__name__ for t in accepted)}"
            )
    for key, (_, required) in known.items():
        if required and key not in values:
            raise LogFormatError(f"{where}: {name!r} record lacks field {key!r} ({cls.__name__})")
    return cls(**values)


MQTT_ENVELOPE = ("seq", "vehicle")
"""What an MQTT event adds to the mission-log record (docs/mqtt.md)."""


def from_message(payload: dict[str, Any], where: str = "MQTT event") -> DurableEvent | None:
    """:func:`from_record` for an event received over MQTT (its envelope ``seq`` and
    ``vehicle`` set aside): a subscriber reads the same classes as the log's readers."""
    return from_record({k: v for k, v in payload.items() if k not in MQTT_ENVELOPE}, where)
