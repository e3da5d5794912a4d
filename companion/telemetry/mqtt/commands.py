"""Operator commands: the JSON payload on <prefix>/uav<i>/cmd or <prefix>/all/cmd, validated."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Literal, Protocol, get_args

from companion.autopilots import FlightMode
from companion.errors import CompanionError

CommandName = Literal["pause", "resume", "abort", "land"]
COMMANDS: tuple[str, ...] = get_args(CommandName)
_FIELDS = {"command", "id"}


class CommandError(CompanionError, ValueError):
    """A command payload that cannot be obeyed; the message says what is wrong."""


@dataclass(frozen=True)
class Command:
    name: CommandName
    id: str | None = None
    """The operator's own reference, echoed in the ``command`` event."""


def parse_command(payload: bytes) -> Command:
    """``{"command": "pause"|"resume"|"abort"|"land", "id": "optional"}`` -> Command."""
    try:
        data = json.loads(payload)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise CommandError(f"not JSON: {exc}") from None
    if not isinstance(data, dict):
        raise CommandError(f"expected a JSON object, got {type(data).__name__}")
    unknown = sorted(set(data) - _FIELDS)
    if unknown:
        raise CommandError(f"unknown field(s) {', '.join(unknown)}; allowed: command, id")
    name = data.get("command")
    if name not in COMMANDS:
        raise CommandError(f"command {name!r}: expected one of {', '.join(COMMANDS)}")
    ref = data.get("id")
    if ref is not None and not (isinstance(ref, str | int) and len(str(ref)) <= 64):
        raise CommandError("id: a string or number of at most 64 characters")
    return Command(name, None if ref is None else str(ref))


class Operated(Protocol):
    """What commands act on (VehicleMission): each returns None when obeyed, else why not."""

    def operator_pause(self) -> str | None: ...

    def operator_resume(self) -> str | None: ...

    def operator_end(self, action: FlightMode, reason: str) -> str | None: ...

    def snapshot(self) -> dict[str, object]: ...

    def emit(self, event: str, **fields: object) -> None: ...


def obey(command: Command, vehicle: Operated) -> str | None:
    """Apply ``command``; None when obeyed, else why not."""
    if command.name == "pause":
        return vehicle.operator_pause()
    if command.name == "resume":
        return vehicle.operator_resume()
    if command.name == "abort":
        return vehicle.operator_end(FlightMode.RTL, "operator abort")
    return vehicle.operator_end(FlightMode.LAND, "operator land")
