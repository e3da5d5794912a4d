"""The lifecycle machine (companion/mission/lifecycle.py): every row of its table walked, the
refused requests, a whole mission, the restart from the durable log, and the table's rendering
in docs/companion.md. Pure: no sockets, no clock."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import pytest

from companion.autopilots import FlightMode
from companion.mission.control import Action, Control, ModeReport, OperatorPause, Refused
from companion.mission.lifecycle import TABLE, Event, Mission, Row, step
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
    Prepared,
    Retried,
    SearchBegun,
    SearchLeft,
    SetpointsBegun,
    Signal,
    TakeoffSent,
    TransitEnded,
)
from companion.mission.phase import Phase
from companion.telemetry import MissionLog, events, read_log

DOCS = Path(__file__).resolve().parents[2] / "docs" / "companion.md"
WAITS: list[Event] = [
    Connected(),
    ControlBack(),
    Located(True),
    Prepared(True, True),
    TakeoffSent(True),
    ClimbStopped(),
    Climbed(True),
    Retried(),
    SetpointsBegun(False, True),
    TransitEnded(True, 60.0),
    SearchLeft(),
]


def at(phase: Phase, **facts: Any) -> Mission:
    return Mission(Control(phase, guided_seen=True), **facts)


@dataclass(frozen=True)
class Case:
    state: Mission
    event: Event
    phase: Phase
    does: tuple[Do | Action, ...]
    facts: dict[str, object] = field(default_factory=dict)
    """Fields of the next state (``ending`` is the control state's)."""


ENDING = at(Phase.SEARCH, end_reason="operator")
CASES = [
    Case(Mission(), Began(True), Phase.DONE, (), {"end_reason": "already ended (mission log)"}),
    Case(Mission(), Began(False), Phase.CONNECT, (Do.CONNECT,), {"end_reason": None}),
    *[Case(replace(ENDING, climbing_by_command=True), e, Phase.SEARCH, (Do.FINISH,),
           {"climbing_by_command": False}) for e in WAITS],
    Case(Mission(), Connected(), Phase.CONNECT, (Do.INSTALL_FENCE, Do.LOCATE)),
    Case(at(Phase.PAUSED), Located(True), Phase.PAUSED, (Do.AWAIT_CONTROL,)),
    Case(at(Phase.LINK_LOST), Located(False), Phase.LINK_LOST, (Do.AWAIT_CONTROL,)),
    Case(at(Phase.SEARCH), Located(True), Phase.SEARCH, (Do.FLY,)),
    Case(Mission(), Located(False), Phase.PREPARE, (Do.PREPARE,)),
    Case(at(Phase.SEARCH), Located(False), Phase.PREPARE, (Do.PREPARE,)),
    Case(at(Phase.PAUSED), ControlBack(), Phase.PAUSED, (Do.LOCATE,)),
    Case(at(Phase.PREPARE), Prepared(False, True), Phase.PREPARE, (Do.RETRY,)),
    Case(at(Phase.PREPARE), Prepared(True, True), Phase.CLIMB, (Do.TAKEOFF,),
         {"climbing_by_command": True}),
    Case(at(Phase.PREPARE), Prepared(True, False), Phase.CLIMB, (Do.CLIMB,),
         {"climbing_by_command": False}),
    Case(at(Phase.CLIMB, climbing_by_command=True), TakeoffSent(False), Phase.CLIMB, (Do.RETRY,),
         {"climbing_by_command": False}),
    Case(at(Phase.CLIMB, climbing_by_command=True), TakeoffSent(True), Phase.CLIMB,
         (Do.AWAIT_CLIMB_STOP,), {"climbing_by_command": True}),
    Case(at(Phase.CLIMB, climbing_by_command=True), ClimbStopped(), Phase.CLIMB,
         (Do.BEGIN_SETPOINTS, Do.CLIMB), {"climbing_by_command": False}),
    Case(at(Phase.PREPARE, climbing_by_command=True), ClimbStopped(), Phase.PREPARE, (Do.RETRY,),
         {"climbing_by_command": False}),
    Case(at(Phase.PAUSED), Climbed(True), Phase.PAUSED, (Do.RETRY,)),
    Case(at(Phase.CLIMB), Climbed(False), Phase.CLIMB, (Do.FINISH,),
         {"end_reason": "climb timeout"}),
    Case(at(Phase.CLIMB), Climbed(True), Phase.CLIMB, (Do.FLY,), {"end_reason": None}),
    Case(at(Phase.CLIMB), Retried(), Phase.CLIMB, (Do.LOCATE,)),
    Case(at(Phase.CLIMB), SetpointsBegun(False, True), Phase.TRANSIT, (Do.TRANSIT,)),
    Case(at(Phase.CLIMB), SetpointsBegun(True, True), Phase.CLIMB, (Do.START_SEARCH,)),
    Case(at(Phase.CLIMB), SetpointsBegun(False, False), Phase.CLIMB, (Do.START_SEARCH,)),
    Case(at(Phase.PAUSED), TransitEnded(False, 60.0), Phase.PAUSED, (Do.LOCATE,)),
    Case(at(Phase.TRANSIT), TransitEnded(False, 90.4), Phase.TRANSIT, (Do.FINISH,),
         {"end_reason": "transit not done in 90 s"}),
    Case(at(Phase.TRANSIT), TransitEnded(True, 90.4), Phase.TRANSIT,
         (Do.SAY_TRANSIT_DONE, Do.START_SEARCH), {"end_reason": None}),
    Case(at(Phase.TRANSIT), SearchBegun(), Phase.SEARCH, (Do.ANNOUNCE_LEVEL, Do.AWAIT_SEARCH_END)),
    Case(at(Phase.PAUSED), SearchLeft(), Phase.PAUSED, (Do.LOCATE,)),
    Case(ENDING, Ending(armed=True), Phase.RETURN, (Do.RECORD_END,), {"ending": True}),
    Case(ENDING, Ending(armed=False), Phase.RETURN, (Do.RECORD_END,), {"ending": False}),
    Case(replace(ENDING, control=Control(Phase.LINK_LOST)), Ending(armed=True), Phase.RETURN,
         (Do.RECORD_END,), {"ending": False}),
    Case(replace(ENDING, control=Control(Phase.RETURN, ending=True)), EndRecorded(),
         Phase.RETURN, (Do.FLY_END_ACTION,)),
    Case(replace(ENDING, control=Control(Phase.RETURN)), EndRecorded(), Phase.DONE, ()),
    Case(replace(ENDING, control=Control(Phase.RETURN, ending=True)), Landed(), Phase.DONE, ()),
    Case(at(Phase.SEARCH), EndRequested("mission time"), Phase.SEARCH, (),
         {"end_reason": "mission time"}),
    Case(ENDING, EndRequested("mission time"), Phase.SEARCH, (), {"end_reason": "operator"}),
    Case(at(Phase.SEARCH), OperatorEnd(FlightMode.LAND, "operator land"), Phase.SEARCH, (),
         {"end_reason": "operator land", "end_action": FlightMode.LAND}),
    Case(at(Phase.SEARCH, signals=1), Signal(), Phase.SEARCH, (Do.EXIT,), {"signals": 2}),
    Case(at(Phase.SEARCH), Signal(), Phase.SEARCH, (Do.SAY_ENDING,),
         {"signals": 1, "end_reason": "operator"}),
    Case(replace(ENDING, end_reason="mission time"), Signal(), Phase.SEARCH, (Do.SAY_ENDING,),
         {"signals": 1, "end_reason": "mission time"}),
    Case(at(Phase.SEARCH), Battery(19, 20), Phase.SEARCH, (), {"end_reason": "battery 19%"}),
    Case(at(Phase.SEARCH), Battery(20, 20), Phase.SEARCH, (), {"end_reason": None}),
    Case(at(Phase.SEARCH), Battery(-1, 20), Phase.SEARCH, (), {"end_reason": None}),
    Case(at(Phase.CLIMB), Battery(5, 20), Phase.CLIMB, (), {"end_reason": None}),
    Case(at(Phase.SEARCH), Battery(45, 20, 35, 10), Phase.SEARCH, (),
         {"end_reason": "battery 45%: home needs 35% + 10% reserve"}),
    Case(at(Phase.SEARCH), Battery(46, 20, 35, 10), Phase.SEARCH, (), {"end_reason": None}),
    Case(at(Phase.SEARCH), Battery(-1, 20, 35, 10), Phase.SEARCH, (), {"end_reason": None}),
    Case(at(Phase.SEARCH), Battery(30, 20, None, 10), Phase.SEARCH, (), {"end_reason": None}),
    Case(at(Phase.TRANSIT), Battery(30, 20, 35, 10), Phase.TRANSIT, (), {"end_reason": None}),
    Case(at(Phase.SEARCH), Battery(15, 20, 35, 10), Phase.SEARCH, (),
         {"end_reason": "battery 15%"}),
    Case(at(Phase.CLIMB), Gps(None), Phase.CLIMB, (), {"inside_fence": False}),
    Case(at(Phase.PREPARE, inside_fence=True), Gps("east of the fence"), Phase.PREPARE, (),
         {"end_reason": None}),
    Case(at(Phase.TRANSIT), Gps(None), Phase.TRANSIT, (), {"inside_fence": True}),
    Case(at(Phase.SEARCH, inside_fence=True), Gps("east of the fence"), Phase.SEARCH,
         (Do.SAY_BREACH,), {"end_reason": "outside the fence: east of the fence"}),
    Case(at(Phase.TRANSIT), Gps("east of the fence"), Phase.TRANSIT, (), {"end_reason": None}),
    Case(replace(ENDING, inside_fence=True), Gps("east of the fence"), Phase.SEARCH, (),
         {"end_reason": "operator"}),
    Case(at(Phase.SEARCH), LinkLost(), Phase.LINK_LOST, ()),
]  # fmt: skip


def _row(state: Mission, event: Event) -> Row:
    return next(r for r in TABLE if isinstance(event, r.events) and r.test(state, event))


@pytest.mark.parametrize("case", CASES, ids=lambda c: f"{c.state.phase.value}-{c.event!r}")
def test_each_transition(case: Case) -> None:
    result = step(case.state, case.event)
    assert not isinstance(result, Refused), result
    state, does = result
    assert state.phase is case.phase
    assert does == case.does
    for name, value in case.facts.items():
        got = state.control.ending if name == "ending" else getattr(state, name)
        assert got == value, name


def test_the_cases_walk_every_row() -> None:
    walked = {id(_row(c.state, c.event)) for c in CASES}
    walked.add(id(_row(ENDING, OperatorEnd(FlightMode.RTL, "x"))))  # the refused row, below
    missing = [f"{r.events[0].__name__}: {r.when}" for r in TABLE if id(r) not in walked]
    assert missing == []


def test_operator_end_while_ending_is_refused() -> None:
    result = step(ENDING, OperatorEnd(FlightMode.LAND, "operator land"))
    assert result == Refused("land: the mission is already ending (operator)")


def test_who_is_in_control_goes_to_the_control_machine() -> None:
    pilot = ModeReport(guided=False, hold=False, setpoints_stalled=False, search_started=True)
    result = step(at(Phase.SEARCH, inside_fence=True), pilot)
    assert result == (at(Phase.PAUSED, inside_fence=True), (Action.WARN_TAKEN_OVER,))
    assert step(at(Phase.CLIMB), OperatorPause()) == Refused("pause: not searching (phase climb)")


ANY_EVENT: list[Event] = [
    Began(False),
    *WAITS,
    SearchBegun(),
    Ending(True),
    EndRecorded(),
    Landed(),
    EndRequested("x"),
    OperatorEnd(FlightMode.RTL, "x"),
    Signal(),
    Battery(5, 20),
    Battery(30, 20, 25, 10),
    Gps(None),
    Gps("east"),
    LinkLost(),
]


@pytest.mark.parametrize("phase", list(Phase))
@pytest.mark.parametrize("end_reason", [None, "operator"])
def test_every_event_has_a_transition_in_every_phase(phase: Phase, end_reason: str | None) -> None:
    for event in ANY_EVENT:
        result = step(at(phase, end_reason=end_reason), event)  # raises when no row matches
        assert isinstance(result, Refused) == (
            isinstance(event, OperatorEnd) and end_reason is not None
        )


class _Vehicle:
    """Answers each step as a vehicle that flies: on the ground, takes off by command."""

    def __init__(self, search_start: float | None) -> None:
        self.search_start = search_start
        self.armed = False

    def outcome(self, do: Do | Action, state: Mission) -> Event | None:
        assert isinstance(do, Do), do
        answers: dict[Do, Event | None] = {
            Do.CONNECT: Connected(),
            Do.LOCATE: Located(self.armed),
            Do.PREPARE: Prepared(True, True),
            Do.TAKEOFF: TakeoffSent(True),
            Do.AWAIT_CLIMB_STOP: ClimbStopped(),
            Do.CLIMB: Climbed(True),
            Do.FLY: SetpointsBegun(self.search_start is not None, start_point=True),
            Do.TRANSIT: TransitEnded(True, 60.0),
            Do.START_SEARCH: SearchBegun(),
            Do.AWAIT_SEARCH_END: SearchLeft(),
            Do.FINISH: Ending(self.armed),
            Do.RECORD_END: EndRecorded(),
            Do.FLY_END_ACTION: Landed(),
        }
        if do is Do.PREPARE:
            self.armed = True
        return answers.get(do)


def _fly(
    began: Began, search_start: float | None
) -> tuple[list[Phase], list[Do | Action], Mission]:
    """Runs the machine as VehicleMission does; the search ends (mission time) once begun."""
    vehicle, state = _Vehicle(search_start), Mission()
    phases, steps = [state.phase], list[Do | Action]()
    pending: list[Event] = [began]
    while pending:
        result = step(state, pending.pop(0))
        assert not isinstance(result, Refused)
        state, does = result
        if state.phase is not phases[-1]:
            phases.append(state.phase)
        for do in does:
            steps.append(do)
            if do is Do.AWAIT_SEARCH_END:
                result = step(state, EndRequested("mission time"))
                assert not isinstance(result, Refused)
                state = result[0]
            outcome = vehicle.outcome(do, state)
            if outcome is not None:
                pending.append(outcome)
    return phases, steps, state


def test_a_whole_mission_from_connect_to_done() -> None:
    phases, steps, state = _fly(Began(False), None)
    assert [p.value for p in phases] == [
        "connect",
        "prepare",
        "climb",
        "transit",
        "search",
        "return",
        "done",
    ]
    assert steps == [
        Do.CONNECT,
        Do.INSTALL_FENCE,
        Do.LOCATE,
        Do.PREPARE,
        Do.TAKEOFF,
        Do.AWAIT_CLIMB_STOP,
        Do.BEGIN_SETPOINTS,
        Do.CLIMB,
        Do.FLY,
        Do.TRANSIT,
        Do.SAY_TRANSIT_DONE,
        Do.START_SEARCH,
        Do.ANNOUNCE_LEVEL,
        Do.AWAIT_SEARCH_END,
        Do.FINISH,
        Do.RECORD_END,
        Do.FLY_END_ACTION,
    ]
    assert state.end_reason == "mission time"


def _log(tmp_path: Path, *records: events.DurableEvent) -> Path:
    path = tmp_path / "vehicle-0.jsonl"
    log = MissionLog(path)
    for t, event in enumerate(records):
        log.emit(float(t), event.NAME, **events.to_fields(event))
    log.close()
    return path


def test_restart_after_the_end_does_nothing(tmp_path: Path) -> None:
    path = _log(
        tmp_path,
        events.Start(0, "paper-fixed", 1, 0, 30.0),
        events.PhaseChange("search", search_start=40.0),
        events.End("mission time", 2),
        events.PhaseChange("return"),
    )
    recovered = read_log(path)
    phases, steps, state = _fly(Began(recovered.ended), recovered.search_start)
    assert phases == [Phase.CONNECT, Phase.DONE]
    assert steps == []
    assert state.end_reason == "already ended (mission log)"


def test_restart_during_the_search_does_not_fly_the_transit_again(tmp_path: Path) -> None:
    path = _log(
        tmp_path,
        events.Start(0, "paper-fixed", 1, 0, 30.0),
        events.PhaseChange("transit"),
        events.PhaseChange("search", search_start=40.0),
        events.Confirmation(10.0, 20.0, 2, 1),
    )
    recovered = read_log(path)
    assert recovered.search_start == 40.0
    assert not recovered.ended
    phases, steps, _ = _fly(Began(recovered.ended), recovered.search_start)
    assert Phase.TRANSIT not in phases
    assert Do.TRANSIT not in steps
    assert steps[steps.index(Do.FLY) + 1] is Do.START_SEARCH


def _rendered() -> list[str]:
    lines = ["| event | condition | sets | next phase | steps |", "| --- | --- | --- | --- | --- |"]
    for row in TABLE:
        event = row.name or ", ".join(f"`{e.__name__}`" for e in row.events)
        then = row.then.value if row.then is not None else "unchanged"
        does = ", ".join(d.value for d in row.does) or "none"
        if row.refused is not None:
            does = f"refused: `{row.refused}`"
        lines.append(f"| {event} | {row.when or 'any'} | {row.sets} | {then} | {does} |")
    return lines


def test_the_docs_show_the_table_as_it_is() -> None:
    docs = DOCS.read_text(encoding="utf-8").splitlines()
    rendered = _rendered()
    start = docs.index(rendered[0])
    assert docs[start : start + len(rendered)] == rendered
