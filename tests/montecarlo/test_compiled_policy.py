"""The engine's compiled policy (step and waypoint draws) answers bit for bit as the numpy one,
and leaves the random stream where the numpy policy leaves it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from mdm_core.search import Observation, SearchPolicy
from mdm_core.search.from_profile import policy_config
from mdm_core.search.levels import AnchorAt, PolicyConfig, Redetection
from mdm_core.search.policy import PolicyState
from mdm_core.search.swarm_iteration import explore
from mdm_montecarlo.kernels.policy_step import CompiledPolicy
from mdm_profiles import builtin_profile

LANES = 2000
TARGETS = 10
REDETECTIONS: tuple[Redetection, ...] = ("recentre", "renew")
ANCHORS: tuple[AnchorAt, ...] = ("vehicle", "target")


def _variants() -> list[PolicyConfig]:
    """Every built-in paper policy's shape, with each out-of-area rule, waypoint origin, anchor
    (vehicle or target), memory rule, redetection rule, the Levy step law and a blind period."""
    base = [policy_config(builtin_profile(name)) for name in ("paper-fixed", "paper-popup")]
    out = []
    for config in base:
        levy_step = tuple(
            dataclasses.replace(level, step_law="levy", step_index=1.5) if k == 1 else level
            for k, level in enumerate(config.levels)
        )
        for rule in ("reflect", "clip", "redraw"):
            for origin in ("position", "anchor"):
                out.append(dataclasses.replace(config, out_of_area=rule, waypoint_origin=origin))
        out.append(dataclasses.replace(config, waypoint_origin="position", anchor_at="target"))
        out.append(dataclasses.replace(config, waypoint_origin="anchor", anchor_at="target"))
        for memory in ("disc", "exact", "none"):
            out.append(
                dataclasses.replace(
                    config, detection_memory=memory, fallback_blind_time=30.0, levels=levy_step
                )
            )
            for rule in REDETECTIONS:
                for anchor in ANCHORS:
                    out.append(
                        dataclasses.replace(
                            config, detection_memory=memory, redetection=rule, anchor_at=anchor
                        )
                    )
        out.append(
            dataclasses.replace(config, confine_to_detection=False, levels=config.levels[:1])
        )
    # A field profile's inset fence (half-planes) redrawn into, from the area's size and anchor.
    field = policy_config(builtin_profile("field-duebendorf"))
    assert field.fence
    out.append(dataclasses.replace(field, out_of_area="redraw", waypoint_origin="position"))
    out.append(dataclasses.replace(field, out_of_area="redraw", waypoint_origin="anchor"))
    return out


def _random_state(policy: SearchPolicy, rng: np.random.Generator) -> PolicyState:
    size = np.array(policy.config.area)
    state = policy.start(rng.uniform(0, size, (LANES, 2)), np.zeros(LANES), rng)
    state.level[:] = rng.integers(0, policy.n_levels, LANES)
    state.anchor[:] = rng.uniform(0, size, (LANES, 2))
    state.entered[:] = rng.uniform(0, 300, LANES)
    blind = rng.random(LANES) < 0.2
    state.blind_until[blind] = rng.uniform(100, 400, blind.sum())
    owners = np.repeat(np.arange(LANES), rng.integers(0, 6, LANES))
    policy.remember(state, owners, rng.uniform(0, size, (owners.size, 2)))
    return state


def _copy(state: PolicyState) -> PolicyState:
    return PolicyState(
        **{f.name: np.copy(getattr(state, f.name)) for f in dataclasses.fields(state)}
    )


def _assert_same_state(a: PolicyState, b: PolicyState) -> None:
    for field in dataclasses.fields(a):
        np.testing.assert_array_equal(getattr(a, field.name), getattr(b, field.name), field.name)


@pytest.mark.parametrize("config", _variants(), ids=lambda c: f"{c.label}")
def test_steps_equal_the_numpy_policy(config: PolicyConfig) -> None:
    numpy_policy, compiled = SearchPolicy(config), CompiledPolicy(config)
    rng = np.random.default_rng(17)
    state = _random_state(numpy_policy, rng)
    mine = _copy(state)
    size = np.array(config.area)
    draws_numpy, draws_compiled = np.random.default_rng(3), np.random.default_rng(3)
    changed = recentred = 0
    for step in range(6):
        lanes = rng.permutation(LANES)[: LANES // 2]
        contacts = rng.random((lanes.size, TARGETS)) < 0.05
        positions = rng.uniform(0, size, (lanes.size, TARGETS, 2))
        # Some contacts on top of a remembered target (they must be dropped as known).
        near = np.flatnonzero(state.memory_count[lanes] > 0)[:50]
        positions[near, 0] = state.memory[lanes[near], 0] + 10.0
        contacts[near, 0] = True
        own = rng.uniform(-200, size + 200, (lanes.size, 2))  # some outside the area
        obs = Observation(
            time=np.full(lanes.size, 100.0 * step) + rng.uniform(0, 100, lanes.size),
            position=own,
            reached=rng.random(lanes.size) < 0.3,
            contacts=contacts,
            contact_positions=positions,
            detections=rng.random((lanes.size, TARGETS)) < 0.1,
        )
        # Some steps exactly at a lane's deadline or at the end of its blind period.
        at_deadline, at_blind = lanes[:100], lanes[100:200]
        obs.time[:100] = (
            state.entered[at_deadline] + numpy_policy._lifetimes[state.level[at_deadline]]
        )
        obs.time[100:200] = state.blind_until[at_blind]
        obs.time[~np.isfinite(obs.time)] = 100.0 * step
        anchors = state.anchor[lanes].copy()
        want = numpy_policy.step(state, lanes, obs, draws_numpy)
        moved = (state.anchor[lanes] != anchors).any(axis=1) & ~want.detected
        recentred += int(moved.sum())
        got = compiled.step(mine, lanes, obs, draws_compiled)
        for name in ("detected", "confirmed", "new_confirmations", "fell_back", "new_waypoint"):
            np.testing.assert_array_equal(getattr(got, name), getattr(want, name), name)
        _assert_same_state(mine, state)
        changed += int(want.detected.sum() + want.confirmed.sum() + want.fell_back.sum())
    # The same place in the random stream afterwards.
    assert draws_numpy.random() == draws_compiled.random()
    # The states really moved: detections, confirmations and fall-backs happened; a
    # redetection rule moved anchors on the last level, and only such a rule did.
    assert changed > 100
    assert (recentred > 50) == (config.redetection != "ignore"), recentred


def test_start_waypoints_equal_the_numpy_policy() -> None:
    config = policy_config(builtin_profile("paper-dynamic"))
    start = np.random.default_rng(1).uniform(0, 20000, (LANES, 2))
    a = SearchPolicy(config).start(start, np.zeros(LANES), np.random.default_rng(2))
    b = CompiledPolicy(config).start(start, np.zeros(LANES), np.random.default_rng(2))
    _assert_same_state(b, a)
    assert not np.array_equal(a.waypoint, start)


@pytest.mark.parametrize("config", _variants())
def test_explore_is_the_swarms_explore_without_its_state(config: PolicyConfig) -> None:
    """CompiledWaypoints.explore: swarm_iteration.explore's level-1 waypoints, bit for bit, and
    the stream left where it leaves it (the swarm engines call it thousands of times)."""
    start = np.random.default_rng(3).uniform(0, 20000, (LANES, 2))
    policy = CompiledPolicy(config)
    ours, theirs = np.random.default_rng(4), np.random.default_rng(4)
    got = policy.explore(start, ours)
    np.testing.assert_array_equal(got, explore(SearchPolicy(config), start, theirs))
    assert ours.bit_generator.state == theirs.bit_generator.state
    assert not np.array_equal(got, start)
