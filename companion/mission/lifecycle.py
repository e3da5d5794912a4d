"""The mission's lifecycle as a pure, synchronous state machine: events in, (state, steps) out.

``VehicleMission`` performs each step (:class:`Do`) and feeds back its outcome; the link, the
operator and the process's signals feed requests at any time. Who is in control (the phase
against the autopilot's modes, the operator's pause) is the machine of control.py, composed
here: its events go to it and its state is part of this one. No I/O, no clock.

:data:`TABLE` is the transition table; docs/companion.md, "The mission's lifecycle", is its
rendering (tests/companion/test_lifecycle.py checks that they agree and walks every row).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

from companion.autopilots import FlightMode
from companion.mission import control
from companion.mission.control import (
    Action,
    Control,
    EndMission,
    LinkRestored,
    ModeReport,
    OperatorPause,
    OperatorResume,
    Refused,
)
from companion.mission.lifecycle_events import (
    Battery,
    Began,
    Climbed,
    ClimbStopped,
    Connected,
    ControlBack,
    Do,
    Ending,
    EndRecorded,
    EndRequested,
    Gps,
    Landed,
    LinkLost,
    Located,
    OperatorEnd,
    Outcome,
    Prepared,
    Request,
    Retried,
    SearchBegun,
    SearchLeft,
    SetpointsBegun,
    Signal,
    TakeoffSent,
    TransitEnded,
)
from companion.mission.phase import Phase

ControlEvent = ModeReport | OperatorPause | OperatorResume | LinkRestored


@dataclass(frozen=True)
class Mission:
    """The state: who is in control, and the facts the lifecycle's transitions depend on."""

    control: Control = field(default_factory=Control)
    end_action: FlightMode = FlightMode.RTL
    """What the end flies: the configured one, or the operator's choice."""
    end_reason: str | None = None
    """Why the search ends; set once (the first reason stands)."""
    signals: int = 0
    inside_fence: bool = False
    """The GPS position was inside the fence since the transit began: from then on, outside
    is a breach (a vehicle may start outside and fly in)."""
    climbing_by_command: bool = False
    """The autopilot's own takeoff climbs: no setpoints until it has stopped."""

    @property
    def phase(self) -> Phase:
        return self.control.phase

    @property
    def ending(self) -> bool:
        return self.end_reason is not None


Event = Outcome | Request | ControlEvent
"""What the machine hears (control.py's ``EndMission`` comes in as :class:`Ending`)."""
Step = tuple[Mission, tuple[Do | Action, ...]]
Guard = Callable[[Mission, Any], bool]
Change = Callable[[Mission, Any], Mission]


def _always(_m: Mission, _e: Any) -> bool:
    return True


def _same(m: Mission, _e: Any) -> Mission:
    return m


def _short_of_home(m: Mission, e: Battery) -> bool:
    """Searching, and no more left than the flight home needs plus the reserve."""
    home = e.home
    return (
        m.phase is Phase.SEARCH
        and e.remaining >= 0
        and home is not None
        and (e.remaining <= home + e.reserve)
    )


def _home_reason(e: Battery) -> str:
    return f"battery {e.remaining}%: home needs {e.home:g}% + {e.reserve:g}% reserve"


def _end(reason: Callable[[Any], str]) -> Change:
    """Set the end reason unless one is set already (the first reason stands)."""
    return lambda m, e: m if m.ending else replace(m, end_reason=reason(e))


@dataclass(frozen=True)
class Row:
    """One transition: for ``events`` when ``test`` holds (``when`` in words), ``change`` the
    state, go to phase ``then`` (None: unchanged) and ask for ``does``; or refuse."""

    events: tuple[type, ...]
    when: str
    then: Phase | None
    does: tuple[Do, ...]
    test: Guard = _always
    change: Change = _same
    refused: str | None = None
    """A refused request: this text, formatted with ``state`` and ``event``."""
    sets: str = ""
    """What ``change`` does, in words (the docs' table)."""
    name: str = ""
    """The events in the docs' table when not their class names."""


_WAITS = (Connected, ControlBack, Located, Prepared, TakeoffSent, ClimbStopped, Climbed, Retried,
          SetpointsBegun, TransitEnded, SearchLeft)  # fmt: skip
"""Outcomes of a step that waited: the end may have been asked meanwhile."""
_OUT_OF_CONTROL = frozenset({Phase.PAUSED, Phase.LINK_LOST})
_WATCHED = frozenset({Phase.TRANSIT, Phase.SEARCH})


def _stop_climbing(m: Mission, _e: Any) -> Mission:
    return replace(m, climbing_by_command=False)


def _end_mission(m: Mission, e: Ending) -> Mission:
    result = control.step(m.control, EndMission(e.armed))
    assert not isinstance(result, Refused)  # the end is never refused
    return replace(m, control=result[0])


def _signal(m: Mission, _e: Signal) -> Mission:
    m = replace(m, signals=m.signals + 1)
    return m if m.ending else replace(m, end_reason="operator")


# fmt: off
TABLE: tuple[Row, ...] = (
    Row((Began,), "the log has an end record (a restart after the end)", Phase.DONE, (),
        lambda m, e: e.ended, lambda m, e: replace(m, end_reason="already ended (mission log)"),
        sets="end: `already ended (mission log)`"),
    Row((Began,), "otherwise", None, (Do.CONNECT,)),
    Row(_WAITS, "the mission is ending", None, (Do.FINISH,), lambda m, e: m.ending,
        _stop_climbing, sets="not climbing by command", name="outcome of a wait"),
    Row((Connected,), "", None, (Do.INSTALL_FENCE, Do.LOCATE)),
    Row((Located,), "paused by someone else, or the link lost", None, (Do.AWAIT_CONTROL,),
        lambda m, e: m.phase in _OUT_OF_CONTROL),
    Row((Located,), "airborne in the guided mode", None, (Do.FLY,),
        lambda m, e: e.airborne_guided),
    Row((Located,), "otherwise", Phase.PREPARE, (Do.PREPARE,)),
    Row((ControlBack,), "", None, (Do.LOCATE,)),
    Row((Prepared,), "not guided or not armed", None, (Do.RETRY,), lambda m, e: not e.ok),
    Row((Prepared,), "the autopilot takes off by command, on the ground", Phase.CLIMB,
        (Do.TAKEOFF,), lambda m, e: e.takeoff,
        lambda m, e: replace(m, climbing_by_command=True), sets="climbing by command"),
    Row((Prepared,), "otherwise (setpoints climb)", Phase.CLIMB, (Do.CLIMB,)),
    Row((TakeoffSent,), "refused or timed out", None, (Do.RETRY,), lambda m, e: not e.accepted,
        _stop_climbing, sets="not climbing by command"),
    Row((TakeoffSent,), "accepted", None, (Do.AWAIT_CLIMB_STOP,)),
    Row((ClimbStopped,), "still climbing", None, (Do.BEGIN_SETPOINTS, Do.CLIMB),
        lambda m, e: m.phase is Phase.CLIMB, _stop_climbing, sets="not climbing by command"),
    Row((ClimbStopped,), "the phase changed (a pilot, a fall-back)", None, (Do.RETRY,),
        change=_stop_climbing, sets="not climbing by command"),
    Row((Climbed,), "the phase changed", None, (Do.RETRY,),
        lambda m, e: m.phase is not Phase.CLIMB),
    Row((Climbed,), "timed out", None, (Do.FINISH,), lambda m, e: not e.reached,
        _end(lambda e: "climb timeout"), sets="end: `climb timeout`"),
    Row((Climbed,), "at the altitude", None, (Do.FLY,)),
    Row((Retried,), "", None, (Do.LOCATE,)),
    Row((SetpointsBegun,), "search not begun, the profile has a start point", Phase.TRANSIT,
        (Do.TRANSIT,), lambda m, e: not e.search_begun and e.start_point),
    Row((SetpointsBegun,), "otherwise", None, (Do.START_SEARCH,)),
    Row((TransitEnded,), "the phase changed", None, (Do.LOCATE,),
        lambda m, e: m.phase is not Phase.TRANSIT),
    Row((TransitEnded,), "timed out", None, (Do.FINISH,), lambda m, e: not e.arrived,
        _end(lambda e: f"transit not done in {e.limit:.0f} s"),
        sets="end: `transit not done in <limit> s`"),
    Row((TransitEnded,), "arrived", None, (Do.SAY_TRANSIT_DONE, Do.START_SEARCH)),
    Row((SearchBegun,), "", Phase.SEARCH, (Do.ANNOUNCE_LEVEL, Do.AWAIT_SEARCH_END)),
    Row((SearchLeft,), "", None, (Do.LOCATE,)),
    Row((Ending,), "the end of control.py (end action or none)", Phase.RETURN,
        (Do.RECORD_END,), change=_end_mission, sets="control: its end"),
    Row((EndRecorded,), "the companion flies the end action", None, (Do.FLY_END_ACTION,),
        lambda m, e: m.control.ending),
    Row((EndRecorded,), "otherwise", Phase.DONE, ()),
    Row((Landed,), "landed and disarmed, or the wait timed out", Phase.DONE, ()),
    Row((EndRequested,), "", None, (), change=_end(lambda e: e.reason), sets="end: its reason"),
    Row((OperatorEnd,), "the mission is ending", None, (), lambda m, e: m.ending,
        refused="{event.action.value}: the mission is already ending ({state.end_reason})"),
    Row((OperatorEnd,), "otherwise", None, (),
        change=lambda m, e: replace(m, end_action=e.action, end_reason=e.reason),
        sets="end action: the operator's; end: its reason"),
    Row((Signal,), "a signal came before", None, (Do.EXIT,), lambda m, e: m.signals > 0,
        lambda m, e: replace(m, signals=m.signals + 1), sets="signals + 1"),
    Row((Signal,), "the first", None, (Do.SAY_ENDING,), change=_signal,
        sets="signals + 1; end: `operator`"),
    Row((Battery,), "searching, known and below the minimum", None, (),
        lambda m, e: m.phase is Phase.SEARCH and 0 <= e.remaining < e.minimum,
        _end(lambda e: f"battery {e.remaining}%"), sets="end: `battery <n>%`"),
    Row((Battery,), "searching, known and at most what home needs plus the reserve", None,
        (), _short_of_home, _end(_home_reason),
        sets="end: `battery <n>%: home needs <h>% + <r>% reserve`"),
    Row((Battery,), "otherwise", None, ()),
    Row((Gps,), "not in transit or search", None, (), lambda m, e: m.phase not in _WATCHED),
    Row((Gps,), "inside the fence", None, (), lambda m, e: e.breach is None,
        lambda m, e: replace(m, inside_fence=True), sets="inside the fence"),
    Row((Gps,), "outside after having been inside, not ending", None, (Do.SAY_BREACH,),
        lambda m, e: m.inside_fence and not m.ending,
        _end(lambda e: f"outside the fence: {e.breach}"),
        sets="end: `outside the fence: <where>`"),
    Row((Gps,), "otherwise (not yet inside, or ending)", None, ()),
    Row((LinkLost,), "", Phase.LINK_LOST, ()),
)
# fmt: on


_ROWS: dict[type, tuple[Row, ...]] = {
    kind: tuple(row for row in TABLE if kind in row.events) for row in TABLE for kind in row.events
}
"""The rows of each event, in the table's order: a lookup per event, not a scan."""


def step(state: Mission, event: Event) -> Step | Refused:
    """The next state and the steps for ``event``; :class:`Refused` for a request that does
    not apply. Who-is-in-control events go to control.py's machine."""
    if isinstance(event, ControlEvent):
        result = control.step(state.control, event)
        if isinstance(result, Refused):
            return result
        return replace(state, control=result[0]), result[1]
    for row in _ROWS.get(type(event), ()):
        if row.test(state, event):
            if row.refused is not None:
                return Refused(row.refused.format(state=state, event=event))
            state = row.change(state, event)
            if row.then is not None:
                state = replace(state, control=control.enter(state.control, row.then))
            return state, row.does
    raise ValueError(f"lifecycle: no transition for {event!r} in phase {state.phase.value}")
