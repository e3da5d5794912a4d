"""Who is in control of the vehicle: the mission's phase and what it knows about the modes, as a
pure, synchronous state machine. Events in, (next state, actions) out; no I/O, no clock.

The lifecycle machine (lifecycle.py) composes it: it passes on what the link reports and the
operator asks, and its own phase changes (prepare, climb, search, return, done) go through
:func:`enter`; ``VehicleMission`` performs the actions. The transition table is in
docs/companion.md, "Who is in control"; tests/companion/test_control.py checks it row by row.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, replace

from companion.mission.phase import Phase

COMMANDING = frozenset({Phase.PREPARE, Phase.CLIMB, Phase.TRANSIT, Phase.SEARCH})
"""Phases in which the companion sends setpoints and may ask for modes."""


class Action(enum.Enum):
    HOLD = "hold"
    """Ask the autopilot to hold (operator pause)."""
    END_ACTION = "end_action"
    """Fly the mission's end action (RTL or LAND) and wait for the landing."""
    WARN_TAKEN_OVER = "warn_taken_over"
    """Say that someone else changed the mode: not commanding."""
    WARN_FALLBACK = "warn_fallback"
    """Say that the autopilot fell back to HOLD after our setpoints stalled: taking it back."""
    SAY_RESUMING = "say_resuming"
    """Say that the vehicle is back in the guided mode: resuming."""


@dataclass(frozen=True)
class Control:
    """The state: the phase and the three facts the transitions depend on."""

    phase: Phase = Phase.CONNECT
    guided_seen: bool = False
    """The vehicle was seen in the guided mode since the companion last (re)asked for it: a
    later other mode is a change by someone else, not a mode the companion is still waiting on."""
    operator_paused: bool = False
    """Paused by the operator (MQTT), not by a pilot's mode change."""
    ending: bool = False
    """The companion asked for the end action itself: the mode change that follows is ours."""


# -- events --------------------------------------------------------------------------------


@dataclass(frozen=True)
class ModeReport:
    """A HEARTBEAT's mode, as the autopilot names it."""

    guided: bool
    hold: bool
    setpoints_stalled: bool
    """Our setpoints had a gap long enough to explain an autopilot's fall-back HOLD."""
    search_started: bool


@dataclass(frozen=True)
class OperatorPause:
    pass


@dataclass(frozen=True)
class OperatorResume:
    pass


@dataclass(frozen=True)
class LinkRestored:
    """The HEARTBEAT is back after a loss; ``before`` is the phase the loss interrupted."""

    before: Phase
    known: bool
    """A HEARTBEAT and the autopilot are known."""
    guided: bool
    armed: bool
    hold: bool


@dataclass(frozen=True)
class EndMission:
    """The search is over (time, targets, battery, operator): what to do with the vehicle."""

    armed: bool


Event = ModeReport | OperatorPause | OperatorResume | LinkRestored | EndMission


@dataclass(frozen=True)
class Refused:
    """An operator request that does not apply in this state, and why."""

    reason: str


Step = tuple[Control, tuple[Action, ...]]


def enter(state: Control, phase: Phase) -> Control:
    """A lifecycle step of the mission's own (prepare, climb, search, return, done, link lost)."""
    return replace(state, phase=phase)


def step(state: Control, event: Event) -> Step | Refused:
    """The next state and the actions for ``event``; :class:`Refused` for an operator request
    that does not apply."""
    if isinstance(event, ModeReport):
        return _on_mode(state, event)
    if isinstance(event, OperatorPause):
        if state.phase is not Phase.SEARCH:
            return Refused(f"pause: not searching (phase {state.phase.value})")
        return replace(state, phase=Phase.PAUSED, operator_paused=True), (Action.HOLD,)
    if isinstance(event, OperatorResume):
        if not (state.operator_paused and state.phase is Phase.PAUSED):
            return Refused(f"resume: not paused by the operator (phase {state.phase.value})")
        return replace(state, phase=Phase.PREPARE, operator_paused=False, guided_seen=False), ()
    if isinstance(event, LinkRestored):
        return _on_link_restored(state, event), ()
    return _on_end(state, event)


def _on_mode(state: Control, mode: ModeReport) -> Step:
    if mode.guided:
        state = replace(state, guided_seen=True)
        if state.phase is Phase.PAUSED and not state.operator_paused:
            phase = Phase.SEARCH if mode.search_started else Phase.PREPARE
            return replace(state, phase=phase), (Action.SAY_RESUMING,)
        return state, ()
    if state.guided_seen and state.phase in COMMANDING and not state.ending:
        if mode.hold and mode.setpoints_stalled:
            # HOLD after our setpoints stalled is the autopilot's own fall-back (PX4 offboard
            # loss): take the vehicle back, as after a link loss. A HOLD while they flowed is
            # someone else's choice.
            return replace(state, phase=Phase.PREPARE, guided_seen=False), (Action.WARN_FALLBACK,)
        return replace(state, phase=Phase.PAUSED), (Action.WARN_TAKEN_OVER,)
    return state, ()


def _on_link_restored(state: Control, link: LinkRestored) -> Control:
    if link.before is Phase.PAUSED or not link.known:
        paused = link.before is Phase.PAUSED
        return replace(state, phase=Phase.PAUSED if paused else Phase.PREPARE, guided_seen=paused)
    if link.guided or not link.armed or link.hold:
        # Still ours, a rebooted vehicle on the ground, or the autopilot's own link-loss HOLD:
        # the lifecycle re-enters the guided mode (taking off again if needed).
        return replace(state, phase=Phase.PREPARE, guided_seen=False)
    return replace(state, phase=Phase.PAUSED)  # a pilot has it


def _on_end(state: Control, end: EndMission) -> Step:
    """Always ``return``; the end action only when the companion still has an armed vehicle
    (never fight a pilot; nothing to bring back on the ground). The mission goes on to ``done``
    once the action is flown, or at once without one."""
    pilot_has_it = state.phase is Phase.LINK_LOST or (
        state.phase is Phase.PAUSED and not state.operator_paused
    )
    if pilot_has_it or not end.armed:
        return replace(state, phase=Phase.RETURN), ()
    return replace(state, phase=Phase.RETURN, ending=True), (Action.END_ACTION,)
