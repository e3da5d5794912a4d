"""The control state machine (companion/mission/control.py), row by row of its transition table
in docs/companion.md, "Who is in control": pure, no sockets, no clock."""

from __future__ import annotations

from dataclasses import replace

import pytest

from companion.mission.control import (
    COMMANDING,
    Action,
    Control,
    EndMission,
    LinkRestored,
    ModeReport,
    OperatorPause,
    OperatorResume,
    Refused,
    enter,
    step,
)
from companion.mission.phase import Phase

GUIDED = ModeReport(guided=True, hold=False, setpoints_stalled=False, search_started=True)
PILOT_MODE = ModeReport(guided=False, hold=False, setpoints_stalled=False, search_started=True)
PILOT_HOLD = ModeReport(guided=False, hold=True, setpoints_stalled=False, search_started=True)
FALLBACK_HOLD = ModeReport(guided=False, hold=True, setpoints_stalled=True, search_started=True)
SEARCHING = Control(Phase.SEARCH, guided_seen=True)


def _applied(state: Control, event: object) -> tuple[Control, tuple[Action, ...]]:
    result = step(state, event)  # type: ignore[arg-type]
    assert not isinstance(result, Refused), result
    return result


def test_operator_pause_while_searching_holds() -> None:
    state, actions = _applied(SEARCHING, OperatorPause())
    assert state.phase is Phase.PAUSED
    assert state.operator_paused
    assert actions == (Action.HOLD,)


@pytest.mark.parametrize("phase", [p for p in Phase if p is not Phase.SEARCH])
def test_operator_pause_outside_the_search_is_refused(phase: Phase) -> None:
    result = step(Control(phase), OperatorPause())
    assert result == Refused(f"pause: not searching (phase {phase.value})")


def test_operator_resume_asks_for_the_guided_mode_again() -> None:
    paused, _ = _applied(SEARCHING, OperatorPause())
    state, actions = _applied(paused, OperatorResume())
    assert state == Control(Phase.PREPARE, guided_seen=False, operator_paused=False)
    assert actions == ()


def test_operator_resume_of_a_pilot_pause_is_refused() -> None:
    paused, _ = _applied(SEARCHING, PILOT_MODE)
    assert isinstance(step(paused, OperatorResume()), Refused)


def test_pilot_pause_ends_when_the_guided_mode_comes_back() -> None:
    paused, _ = _applied(SEARCHING, PILOT_MODE)
    state, actions = _applied(paused, GUIDED)
    assert state.phase is Phase.SEARCH
    assert actions == (Action.SAY_RESUMING,)
    before_search = replace(GUIDED, search_started=False)
    assert _applied(paused, before_search)[0].phase is Phase.PREPARE


def test_guided_mode_does_not_end_an_operator_pause() -> None:
    paused, _ = _applied(SEARCHING, OperatorPause())
    state, actions = _applied(paused, GUIDED)
    assert state.phase is Phase.PAUSED
    assert actions == ()


@pytest.mark.parametrize("phase", sorted(COMMANDING, key=str))
def test_fallback_hold_after_a_setpoint_gap_is_taken_back(phase: Phase) -> None:
    state, actions = _applied(Control(phase, guided_seen=True), FALLBACK_HOLD)
    assert state.phase is Phase.PREPARE
    assert not state.guided_seen
    assert actions == (Action.WARN_FALLBACK,)


@pytest.mark.parametrize("report", [PILOT_MODE, PILOT_HOLD])
@pytest.mark.parametrize("phase", sorted(COMMANDING, key=str))
def test_another_mode_while_commanding_pauses(phase: Phase, report: ModeReport) -> None:
    state, actions = _applied(Control(phase, guided_seen=True), report)
    assert state.phase is Phase.PAUSED
    assert actions == (Action.WARN_TAKEN_OVER,)


@pytest.mark.parametrize(
    "state",
    [Control(Phase.PREPARE, guided_seen=False), Control(Phase.RETURN, guided_seen=True, ending=True),
     Control(Phase.SEARCH, guided_seen=True, ending=True), Control(Phase.DONE, guided_seen=True)],
)  # fmt: skip
def test_other_modes_before_guided_was_seen_or_while_ending_change_nothing(state: Control) -> None:
    assert _applied(state, PILOT_MODE) == (state, ())


def test_link_restored_after_a_pause_stays_paused() -> None:
    event = LinkRestored(Phase.PAUSED, known=True, guided=True, armed=True, hold=False)
    state, _ = _applied(Control(Phase.LINK_LOST), event)
    assert state.phase is Phase.PAUSED
    assert state.guided_seen


@pytest.mark.parametrize(
    ("guided", "armed", "hold"), [(True, True, False), (False, False, False), (False, True, True)]
)
def test_link_restored_ours_disarmed_or_hold_prepares_again(
    guided: bool, armed: bool, hold: bool
) -> None:
    event = LinkRestored(Phase.SEARCH, known=True, guided=guided, armed=armed, hold=hold)
    state, _ = _applied(Control(Phase.LINK_LOST, guided_seen=True), event)
    assert state.phase is Phase.PREPARE
    assert not state.guided_seen


def test_link_restored_in_a_pilots_mode_pauses() -> None:
    event = LinkRestored(Phase.SEARCH, known=True, guided=False, armed=True, hold=False)
    assert _applied(Control(Phase.LINK_LOST), event)[0].phase is Phase.PAUSED


def test_link_restored_before_the_vehicle_is_known_prepares() -> None:
    event = LinkRestored(Phase.CONNECT, known=False, guided=False, armed=False, hold=False)
    assert _applied(Control(Phase.LINK_LOST), event)[0].phase is Phase.PREPARE


@pytest.mark.parametrize(
    "state", [Control(Phase.LINK_LOST), Control(Phase.PAUSED, guided_seen=True)]
)
def test_end_never_fights_a_pilot_or_a_lost_link(state: Control) -> None:
    ended, actions = _applied(state, EndMission(armed=True))
    assert ended.phase is Phase.RETURN
    assert actions == ()


def test_end_on_the_ground_flies_nothing() -> None:
    assert _applied(SEARCHING, EndMission(armed=False))[1] == ()


@pytest.mark.parametrize(
    "state", [SEARCHING, Control(Phase.CLIMB), Control(Phase.PAUSED, operator_paused=True)]
)
def test_end_of_an_armed_vehicle_we_command_flies_the_end_action(state: Control) -> None:
    ended, actions = _applied(state, EndMission(armed=True))
    assert ended.phase is Phase.RETURN
    assert ended.ending
    assert actions == (Action.END_ACTION,)
    # The end action's own mode change is not a pilot's.
    assert _applied(ended, PILOT_MODE) == (ended, ())


def test_lifecycle_steps_change_only_the_phase() -> None:
    state = Control(Phase.PAUSED, guided_seen=True, operator_paused=True, ending=True)
    assert enter(state, Phase.SEARCH) == replace(state, phase=Phase.SEARCH)
