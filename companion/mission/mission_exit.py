"""How a companion ends: exit status 0 only when the vehicle was seen landed and disarmed (or
the end action was accepted where the run asked not to wait for the landing) after a mission
that was not cut short by a fault; anything else is 1, with the cause in one line that says
where the vehicle was left."""

from __future__ import annotations

import math
from dataclasses import dataclass

from companion.autopilots import Autopilot
from companion.link.messages import Heartbeat, LocalPosition

FAULT_ENDS = ("climb timeout", "transit not done", "outside the fence", "battery")
"""End reasons (their beginnings) of a mission cut short by a fault: the exit is 1 however
safely the vehicle came down (a run that failed never reports success)."""


@dataclass(frozen=True)
class MissionExit:
    status: int
    cause: str


def where(pos: LocalPosition | None, home: tuple[float, float] | None) -> str:
    """``at 30 m, 1.2 km from home`` (the last valid position; home: where it was first seen
    on the ground)."""
    if pos is None:
        return "position never known"
    alt = f"at {-pos.down:.0f} m"
    if home is None:
        return f"{alt}, at ({pos.north:.0f}, {pos.east:.0f}) m (home not seen)"
    d = math.hypot(pos.north - home[0], pos.east - home[1])
    far = f"{d / 1000:.1f} km" if d >= 1000 else f"{d:.0f} m"
    return f"{alt}, {far} from home"


def final_exit(
    exit: MissionExit | None,
    heartbeat: Heartbeat | None,
    autopilot: Autopilot | None,
    where: str,
    failsafe: str | None,
    end_reason: str | None = None,
) -> MissionExit:
    """The ``exit`` record: ``exit`` when the end's wait or the link's loss set it, else from
    what the vehicle was last seen doing (``where``: :func:`where`'s words); never 0 after the
    position failsafe (``failsafe``: its cause, if it ended the mission) or after a mission
    that ended for a fault (``end_reason`` one of :data:`FAULT_ENDS`)."""
    if exit is None:
        if heartbeat is None:
            exit = MissionExit(1, "the vehicle was never heard")
        elif heartbeat.armed:
            mode = autopilot.mode_name(heartbeat.custom_mode) if autopilot is not None else "?"
            exit = MissionExit(1, f"left armed in {mode}, {where}")
        else:
            exit = MissionExit(0, "disarmed on the ground")
    if failsafe is not None and exit.status == 0:
        exit = MissionExit(1, f"failsafe ({failsafe}); {exit.cause}")
    if end_reason is not None and end_reason.startswith(FAULT_ENDS) and exit.status == 0:
        exit = MissionExit(1, f"{end_reason}; {exit.cause}")
    return exit
