"""The batched MDM search policy: level switching, memory, fall-back and waypoint draws."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.typing import ArrayLike

from mdm_core.search.distributions import Brownian, Levy, Uniform
from mdm_core.search.levels import (
    DecayIndex,
    DetectionMemory,
    Level,
    OutOfArea,
    PolicyConfig,
    StepLaw,
)
from mdm_core.search.policy import Observation, PolicyState, SearchPolicy

AREA = 20_000.0
R1, R2 = 2000.0, 400.0
DELTA1, DELTA2 = 4000.0, 2000.0
CENTRE = np.array([10_000.0, 10_000.0])


def mdm(
    *,
    out_of_area: OutOfArea = "reflect",
    confine: bool = True,
    origin: str = "position",
    step2: float = DELTA2,
    law2: StepLaw = "fixed",
    memory_radius: float = 400.0,
    detection_memory: DetectionMemory = "disc",
    blind: float = 0.0,
) -> SearchPolicy:
    levels = (
        Level(sampler=Levy(), step=DELTA1, sensor_radius=R1),
        Level(sampler=Brownian(), step=step2, sensor_radius=R2, index=DecayIndex(), step_law=law2),
    )
    return SearchPolicy(
        PolicyConfig(
            levels=levels,
            area=(AREA, AREA),
            out_of_area=out_of_area,
            waypoint_origin="anchor" if origin == "anchor" else "position",
            confine_to_detection=confine,
            memory_radius=memory_radius,
            detection_memory=detection_memory,
            fallback_blind_time=blind,
        )
    )


def sss() -> SearchPolicy:
    level = Level(sampler=Uniform(), step=DELTA1, sensor_radius=R2)
    return SearchPolicy(PolicyConfig(levels=(level,), area=(AREA, AREA)))


def obs(
    time: ArrayLike,
    position: ArrayLike,
    contacts: np.ndarray | None = None,
    contact_positions: ArrayLike | None = None,
    reached: ArrayLike = False,
) -> Observation:
    where = np.atleast_2d(np.asarray(position, dtype=float))
    n = len(where)
    if contacts is None:
        contacts = np.zeros((n, 1), dtype=bool)
    contacts = np.atleast_2d(contacts)
    if contact_positions is None:
        contact_positions = np.zeros((*contacts.shape, 2))
    return Observation(
        time=np.broadcast_to(np.asarray(time, dtype=float), (n,)).copy(),
        position=where,
        reached=np.broadcast_to(np.asarray(reached, dtype=bool), (n,)).copy(),
        contacts=contacts,
        contact_positions=np.broadcast_to(
            np.asarray(contact_positions, dtype=float), (*contacts.shape, 2)
        ).copy(),
    )


def start_one(
    policy: SearchPolicy, position: np.ndarray = CENTRE, time: float = 0.0, seed: int = 0
) -> tuple[PolicyState, np.random.Generator]:
    rng = np.random.default_rng(seed)
    state = policy.start(np.array([position]), np.array([time]), rng)
    return state, rng


ONE = np.array([0])


def detect(
    policy: SearchPolicy, state: PolicyState, rng: np.random.Generator, t: float, at: np.ndarray
) -> None:
    target = at + np.array([500.0, 0.0])
    policy.step(state, ONE, obs(t, at, np.array([[True]]), target), rng)


def test_start_puts_everyone_on_level_1_with_waypoint_one_step_away() -> None:
    policy = mdm()
    rng = np.random.default_rng(1)
    pos = np.tile(CENTRE, (50, 1))
    state = policy.start(pos, np.zeros(50), rng)
    assert np.all(state.level == 0)
    np.testing.assert_allclose(np.linalg.norm(state.waypoint - pos, axis=1), DELTA1, rtol=1e-12)
    assert np.all(np.isnan(policy.index_value(state, np.zeros(50))))
    assert np.all(np.isinf(policy.deadline(state)))


def test_detection_on_level_1_moves_to_level_2_with_anchor_at_detection_position() -> None:
    policy = mdm()
    state, rng = start_one(policy)
    here = np.array([9000.0, 11000.0])
    out = policy.step(state, ONE, obs(42.0, here, np.array([[True]]), [[[9500.0, 11000.0]]]), rng)
    assert out.detected.tolist() == [True]
    assert out.confirmed.tolist() == [False]
    assert out.new_waypoint.tolist() == [True]
    assert state.level.tolist() == [1]
    np.testing.assert_array_equal(state.anchor[0], here)
    assert state.entered[0] == 42.0
    assert policy.sensor_radius(state).tolist() == [R2]
    assert policy.uses_confirmation_sensor(state).tolist() == [True]
    assert int(state.memory_count[0]) == 0


def test_confirmation_on_level_2_remembers_target_and_returns_to_level_1() -> None:
    policy = mdm()
    state, rng = start_one(policy)
    detect(policy, state, rng, 10.0, CENTRE)
    target = np.array([10_100.0, 10_050.0])
    out = policy.step(state, ONE, obs(50.0, CENTRE, np.array([[True]]), target), rng)
    assert out.confirmed.tolist() == [True]
    assert out.detected.tolist() == [False]
    assert out.new_confirmations.tolist() == [[True]]
    assert state.level.tolist() == [0]
    assert state.entered[0] == 50.0
    assert int(state.memory_count[0]) == 1
    np.testing.assert_array_equal(state.memory[0, 0], target)


def test_two_targets_confirmed_at_once_are_both_remembered() -> None:
    policy = mdm()
    state, rng = start_one(policy)
    detect(policy, state, rng, 10.0, CENTRE)
    targets = np.array([[[10_100.0, 10_000.0], [9_000.0, 9_000.0]]])
    out = policy.step(state, ONE, obs(20.0, CENTRE, np.array([[True, True]]), targets), rng)
    assert out.new_confirmations.tolist() == [[True, True]]
    assert int(state.memory_count[0]) == 2
    np.testing.assert_array_equal(state.memory[0, :2], targets[0])


def test_exact_memory_ignores_a_contact_within_memory_radius_of_a_confirmed_target() -> None:
    policy = mdm(memory_radius=400.0, detection_memory="exact")
    state, rng = start_one(policy)
    detect(policy, state, rng, 10.0, CENTRE)
    target = np.array([10_000.0, 10_000.0])
    policy.step(state, ONE, obs(20.0, CENTRE, np.array([[True]]), target), rng)
    waypoint = state.waypoint.copy()

    near = target + np.array([400.0, 0.0])
    out = policy.step(state, ONE, obs(30.0, CENTRE, np.array([[True]]), near), rng)
    assert out.detected.tolist() == [False]
    assert state.level.tolist() == [0]
    np.testing.assert_array_equal(state.waypoint, waypoint)

    beyond = target + np.array([400.001, 0.0])
    out = policy.step(state, ONE, obs(40.0, CENTRE, np.array([[True]]), beyond), rng)
    assert out.detected.tolist() == [True]
    assert state.level.tolist() == [1]


def test_unused_memory_rows_do_not_hide_a_target_at_the_origin() -> None:
    policy = mdm()
    state, rng = start_one(policy, position=np.array([100.0, 100.0]))
    out = policy.step(state, ONE, obs(1.0, [100.0, 100.0], np.array([[True]]), [0.0, 0.0]), rng)
    assert out.detected.tolist() == [True]


def test_memory_grows_past_its_initial_capacity() -> None:
    policy = mdm()
    state, _ = start_one(policy)
    points = [np.array([[1000.0 * k, 0.0]]) for k in range(9)]
    for p in points:
        policy.remember(state, ONE, p)
    assert int(state.memory_count[0]) == 9
    np.testing.assert_array_equal(state.memory[0, :9], np.concatenate(points))
    assert policy.known(state, ONE, np.array([[[8000.0, 100.0], [500.0, 5000.0]]])).tolist() == [
        [True, False]
    ]


def test_index_value_at_the_lifetime_equals_index_min() -> None:
    policy = mdm()
    state, rng = start_one(policy)
    detect(policy, state, rng, 100.0, CENTRE)
    life = DecayIndex().lifetime
    assert policy.deadline(state)[0] == pytest.approx(100.0 + life, abs=1e-12)
    assert policy.index_value(state, np.array([100.0]))[0] == pytest.approx(0.85, abs=1e-12)
    assert policy.index_value(state, np.array([100.0 + life]))[0] == pytest.approx(0.2, abs=1e-9)


def test_level_2_is_kept_just_before_the_lifetime() -> None:
    policy = mdm()
    state, rng = start_one(policy)
    detect(policy, state, rng, 0.0, CENTRE)
    life = DecayIndex().lifetime
    out = policy.step(state, ONE, obs(life - 1e-6, CENTRE), rng)
    assert out.fell_back.tolist() == [False]
    assert out.new_waypoint.tolist() == [False]
    assert state.level.tolist() == [1]


def test_level_2_falls_back_to_level_1_at_the_lifetime() -> None:
    policy = mdm()
    state, rng = start_one(policy)
    detect(policy, state, rng, 0.0, CENTRE)
    out = policy.step(state, ONE, obs(DecayIndex().lifetime, CENTRE), rng)
    assert out.fell_back.tolist() == [True]
    assert out.new_waypoint.tolist() == [True]
    assert state.level.tolist() == [0]
    np.testing.assert_allclose(np.linalg.norm(state.waypoint[0] - CENTRE), DELTA1, rtol=1e-12)


def test_step_at_the_reported_deadline_always_falls_back() -> None:
    """A scheduler steps vehicles at deadline(); rounding must not keep them on level 2."""
    policy = mdm()
    entered = np.linspace(0.1, 5000.0, 400)
    rng = np.random.default_rng(3)
    state = policy.start(np.tile(CENTRE, (400, 1)), np.zeros(400), rng)
    lanes = np.arange(400)
    hit = np.ones((400, 1), dtype=bool)
    policy.step(state, lanes, obs(entered, np.tile(CENTRE, (400, 1)), hit, CENTRE), rng)
    assert np.all(state.level == 1)
    out = policy.step(state, lanes, obs(policy.deadline(state), np.tile(CENTRE, (400, 1))), rng)
    assert np.all(out.fell_back)
    assert np.all(state.level == 0)


def test_level_1_never_falls_back() -> None:
    policy = mdm()
    state, rng = start_one(policy)
    out = policy.step(state, ONE, obs(1e9, CENTRE), rng)
    assert out.fell_back.tolist() == [False]
    assert state.level.tolist() == [0]


def test_single_sensor_search_confirmation_keeps_level_and_waypoint() -> None:
    policy = sss()
    state, rng = start_one(policy)
    waypoint = state.waypoint.copy()
    out = policy.step(state, ONE, obs(5.0, CENTRE, np.array([[True]]), CENTRE), rng)
    assert out.confirmed.tolist() == [True]
    assert out.detected.tolist() == [False]
    assert out.new_waypoint.tolist() == [False]
    assert state.level.tolist() == [0]
    np.testing.assert_array_equal(state.waypoint, waypoint)
    assert int(state.memory_count[0]) == 1


def test_three_level_policy_climbs_one_level_per_detection() -> None:
    levels = (
        Level(sampler=Levy(), step=4000.0, sensor_radius=3000.0),
        Level(sampler=Brownian(), step=2000.0, sensor_radius=1500.0, index=DecayIndex()),
        Level(sampler=Brownian(), step=1000.0, sensor_radius=300.0, index=DecayIndex()),
    )
    policy = SearchPolicy(PolicyConfig(levels=levels, area=(AREA, AREA)))
    state, rng = start_one(policy)
    for t, expected in ((1.0, 1), (2.0, 2)):
        out = policy.step(state, ONE, obs(t, CENTRE, np.array([[True]]), CENTRE), rng)
        assert out.detected.tolist() == [True]
        assert state.level.tolist() == [expected]
    out = policy.step(state, ONE, obs(3.0, CENTRE, np.array([[True]]), CENTRE), rng)
    assert out.confirmed.tolist() == [True]
    assert state.level.tolist() == [0]


def test_reached_waypoint_gets_a_new_one_delta_away_on_each_level() -> None:
    policy = mdm()
    rng = np.random.default_rng(4)
    n = 200
    pos = np.tile(CENTRE, (n, 1))
    state = policy.start(pos, np.zeros(n), rng)
    lanes = np.arange(n)
    half = np.zeros((n, 1), dtype=bool)
    half[::2] = True
    policy.step(state, lanes, obs(1.0, pos, half, CENTRE), rng)
    out = policy.step(state, lanes, obs(2.0, pos, reached=True), rng)
    assert np.all(out.new_waypoint)
    step = np.linalg.norm(state.waypoint - pos, axis=1)
    np.testing.assert_allclose(step[::2], DELTA2, rtol=1e-12)
    np.testing.assert_allclose(step[1::2], DELTA1, rtol=1e-12)


def test_waypoint_is_kept_while_not_reached_and_nothing_happens() -> None:
    policy = mdm()
    state, rng = start_one(policy)
    waypoint = state.waypoint.copy()
    out = policy.step(state, ONE, obs(3.0, CENTRE + 10.0), rng)
    assert out.new_waypoint.tolist() == [False]
    np.testing.assert_array_equal(state.waypoint, waypoint)


@pytest.mark.parametrize("rule", ["reflect", "clip", "redraw"])
def test_new_waypoints_stay_inside_the_area_near_a_corner(rule: OutOfArea) -> None:
    policy = mdm(out_of_area=rule)
    rng = np.random.default_rng(5)
    n = 2000
    pos = np.tile([10.0, AREA - 10.0], (n, 1))
    state = policy.start(pos, np.zeros(n), rng)
    for t in range(1, 4):
        policy.step(state, np.arange(n), obs(float(t), pos, reached=True), rng)
        assert np.all(state.waypoint >= 0.0)
        assert np.all(state.waypoint <= AREA)


def test_redraw_keeps_the_fixed_step_length_next_to_a_wall() -> None:
    policy = mdm(out_of_area="redraw")
    rng = np.random.default_rng(6)
    pos = np.tile([10.0, 10_000.0], (1000, 1))
    state = policy.start(pos, np.zeros(1000), rng)
    np.testing.assert_allclose(np.linalg.norm(state.waypoint - pos, axis=1), DELTA1, rtol=1e-12)
    assert np.all(state.waypoint[:, 0] >= 0.0)


@pytest.mark.parametrize(("step2", "law"), [(2000.0, "levy"), (7000.0, "fixed"), (5000.0, "fixed")])
def test_confined_level_2_waypoints_stay_within_r1_of_the_anchor(
    step2: float, law: StepLaw
) -> None:
    policy = mdm(step2=step2, law2=law)
    rng = np.random.default_rng(7)
    n = 3000
    anchor = np.tile(CENTRE, (n, 1))
    state = policy.start(anchor, np.zeros(n), rng)
    lanes = np.arange(n)
    policy.step(state, lanes, obs(1.0, anchor, np.ones((n, 1), dtype=bool), CENTRE), rng)
    pos = anchor.copy()
    for t in range(2, 6):
        assert np.all(np.linalg.norm(state.waypoint - anchor, axis=1) <= R1 + 1e-9)
        pos = state.waypoint.copy()
        policy.step(state, lanes, obs(float(t), pos, reached=True), rng)
    assert np.all(state.level == 1)


def test_unconfined_level_2_waypoints_may_leave_the_detection_disc() -> None:
    policy = mdm(confine=False, step2=3000.0)
    state, rng = start_one(policy)
    detect(policy, state, rng, 1.0, CENTRE)
    assert np.linalg.norm(state.waypoint[0] - CENTRE) == pytest.approx(3000.0, rel=1e-12)


def test_anchor_origin_draws_level_2_waypoints_around_the_detection_point() -> None:
    policy = mdm(origin="anchor", step2=1000.0)
    state, rng = start_one(policy)
    detect(policy, state, rng, 1.0, CENTRE)
    elsewhere = CENTRE + np.array([700.0, -300.0])
    for t in (2.0, 3.0, 4.0):
        policy.step(state, ONE, obs(t, elsewhere, reached=True), rng)
        assert np.linalg.norm(state.waypoint[0] - CENTRE) == pytest.approx(1000.0, rel=1e-12)


def test_levy_step_law_caps_steps_at_step_cap_times_delta() -> None:
    policy = mdm(confine=False, law2="levy", step2=100.0)
    rng = np.random.default_rng(8)
    n = 3000
    pos = np.tile(CENTRE, (n, 1))
    state = policy.start(pos, np.zeros(n), rng)
    policy.step(state, np.arange(n), obs(1.0, pos, np.ones((n, 1), dtype=bool), CENTRE), rng)
    steps = np.linalg.norm(state.waypoint - pos, axis=1)
    assert steps.max() == pytest.approx(500.0, rel=1e-12)
    assert 0.0 < steps.min() < 100.0


def test_stepping_some_lanes_leaves_the_others_untouched() -> None:
    policy = mdm()
    rng = np.random.default_rng(9)
    pos = np.tile(CENTRE, (4, 1))
    state = policy.start(pos, np.zeros(4), rng)
    before = (state.level.copy(), state.waypoint.copy(), state.entered.copy())
    lanes = np.array([1, 3])
    policy.step(state, lanes, obs(5.0, pos[lanes], np.ones((2, 1), dtype=bool), CENTRE), rng)
    assert state.level.tolist() == [0, 1, 0, 1]
    for k in (0, 2):
        np.testing.assert_array_equal(state.waypoint[k], before[1][k])
        assert state.entered[k] == before[2][k]


def test_batched_step_switches_levels_like_one_by_one_steps() -> None:
    """Levels, anchors, entry times and memory do not depend on how lanes are batched.

    (Waypoints do: a batch draws its random numbers in a different order.)
    """
    policy = mdm()
    n, m = 12, 3
    data = np.random.default_rng(10)
    pos = data.uniform(0, AREA, size=(6, n, 2))
    hits = data.random((6, n, m)) < 0.3
    targets = data.uniform(0, AREA, size=(6, n, m, 2))
    times = np.array([0.0, 10.0, 20.0, 400.0, 410.0, 1000.0])

    batched = policy.start(pos[0], np.zeros(n), np.random.default_rng(11))
    singles = [policy.start(pos[0][[i]], np.zeros(1), np.random.default_rng(12)) for i in range(n)]
    rng_a, rng_b = np.random.default_rng(13), np.random.default_rng(14)
    for k in range(1, 6):
        policy.step(batched, np.arange(n), obs(times[k], pos[k], hits[k], targets[k]), rng_a)
        for i, single in enumerate(singles):
            policy.step(
                single, ONE, obs(times[k], pos[k][[i]], hits[k][[i]], targets[k][[i]]), rng_b
            )
    for i, single in enumerate(singles):
        assert batched.level[i] == single.level[0]
        assert batched.entered[i] == single.entered[0]
        np.testing.assert_array_equal(batched.anchor[i], single.anchor[0])
        count = int(single.memory_count[0])
        assert batched.memory_count[i] == count
        np.testing.assert_array_equal(batched.memory[i, :count], single.memory[0, :count])


def _confirmed_at(
    policy: SearchPolicy, target: np.ndarray
) -> tuple[PolicyState, np.random.Generator]:
    """A vehicle at CENTRE that detected and confirmed ``target`` (back on level 1)."""
    state, rng = start_one(policy)
    detect(policy, state, rng, 10.0, CENTRE)
    policy.step(state, ONE, obs(20.0, CENTRE, np.array([[True]]), target), rng)
    assert state.level.tolist() == [0]
    return state, rng


def test_disc_memory_ignores_detections_only_while_a_confirmed_target_is_within_r1() -> None:
    # The detection sensor gives no position: the contact's position is not looked at (here it
    # is far from the confirmed target), only where the vehicle is.
    policy = mdm(detection_memory="disc")
    target = CENTRE + np.array([300.0, 0.0])
    state, rng = _confirmed_at(policy, target)
    elsewhere = np.array([5_000.0, 5_000.0])
    inside = target + np.array([R1 - 1.0, 0.0])
    out = policy.step(state, ONE, obs(30.0, inside, np.array([[True]]), elsewhere), rng)
    assert out.detected.tolist() == [False]
    outside = target + np.array([R1 + 1.0, 0.0])
    out = policy.step(state, ONE, obs(40.0, outside, np.array([[True]]), target), rng)
    assert out.detected.tolist() == [True]


def test_no_detection_memory_redetects_the_confirmed_target() -> None:
    policy = mdm(detection_memory="none")
    target = CENTRE + np.array([300.0, 0.0])
    state, rng = _confirmed_at(policy, target)
    out = policy.step(state, ONE, obs(30.0, CENTRE, np.array([[True]]), target), rng)
    assert out.detected.tolist() == [True]
    # The confirmation sensor gives the position: the same target is not confirmed twice.
    out = policy.step(state, ONE, obs(31.0, CENTRE, np.array([[True]]), target), rng)
    assert out.confirmed.tolist() == [False]


def test_blind_time_after_a_fall_back_ignores_detections_then_ends() -> None:
    policy = mdm(blind=100.0)
    state, rng = start_one(policy)
    detect(policy, state, rng, 0.0, CENTRE)
    life = DecayIndex().lifetime
    out = policy.step(state, ONE, obs(life, CENTRE), rng)
    assert out.fell_back.tolist() == [True]
    assert policy.deadline(state)[0] == pytest.approx(life + 100.0)
    out = policy.step(state, ONE, obs(life + 50.0, CENTRE, np.array([[True]]), CENTRE), rng)
    assert out.detected.tolist() == [False]
    out = policy.step(state, ONE, obs(life + 100.0, CENTRE), rng)
    assert policy.deadline(state)[0] == np.inf
    out = policy.step(state, ONE, obs(life + 101.0, CENTRE, np.array([[True]]), CENTRE), rng)
    assert out.detected.tolist() == [True]


def test_index_that_starts_at_its_maximum() -> None:
    printed, top = DecayIndex(kappa=180.0), DecayIndex(kappa=180.0, start="max")
    assert printed.value(np.array(0.0)) == pytest.approx(0.85)
    assert top.value(np.array(0.0)) == pytest.approx(0.95)
    assert top.value(np.array(top.lifetime)) == pytest.approx(0.2)
    assert top.lifetime == pytest.approx(180.0 * np.log(0.85 / 0.1))
