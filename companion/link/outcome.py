"""What became of a command sent to the vehicle: accepted, denied (with the vehicle's reason) or
timed out. Truthy only when accepted, so ``if not await link.arm()`` reads as before."""

from __future__ import annotations

import enum
from dataclasses import dataclass


class Outcome(enum.Enum):
    ACCEPTED = "accepted"
    DENIED = "denied"
    """The vehicle answered no (COMMAND_ACK result other than ACCEPTED, or an action error)."""
    TIMED_OUT = "timed_out"
    """No final answer after every transport retry."""


@dataclass(frozen=True)
class CommandResult:
    """One command's outcome."""

    what: str
    """The command or parameter, by name (e.g. ``MAV_CMD_COMPONENT_ARM_DISARM``)."""
    outcome: Outcome
    result: int | None = None
    """MAV_RESULT of the COMMAND_ACK, when there was one."""
    reason: str | None = None
    """The vehicle's own words: the STATUSTEXT it sent with the refusal, or MAVSDK's error."""

    def __bool__(self) -> bool:
        return self.outcome is Outcome.ACCEPTED

    def describe(self) -> str:
        """One line for the console: ``MAV_CMD_X denied (result 4): Arm: Throttle ...``."""
        text = f"{self.what} {self.outcome.value.replace('_', ' ')}"
        if self.result is not None:
            text += f" (result {self.result})"
        return f"{text}: {self.reason}" if self.reason else text


def accepted(what: str) -> CommandResult:
    return CommandResult(what, Outcome.ACCEPTED, 0)


def denied(what: str, reason: str, result: int | None = None) -> CommandResult:
    return CommandResult(what, Outcome.DENIED, result, reason)


def timed_out(what: str, reason: str | None = None) -> CommandResult:
    return CommandResult(what, Outcome.TIMED_OUT, None, reason)
