"""A field profile's fence as the policy reads it: half-planes of the inset fence, and waypoints
redrawn inside them (docs/model.md, "Search near the fence")."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from companion.fence_from_profile import guidance_fence
from mdm_core.search import Observation, SearchPolicy
from mdm_core.search.from_profile import policy_config
from mdm_core.world.fence_planes import fence_half_planes, inset_half_planes
from mdm_profiles import builtin_profile

FIELD = builtin_profile("field-duebendorf")


def _inside(planes: tuple[tuple[float, float, float], ...], points: np.ndarray) -> np.ndarray:
    return np.asarray(
        np.all([points[:, 0] * n + points[:, 1] * e >= o for n, e, o in planes], axis=0)
    )


def test_the_half_planes_hold_exactly_what_the_companions_guidance_fence_holds() -> None:
    fence = guidance_fence(FIELD)
    points = np.random.default_rng(1).uniform([-100, -100], [1300, 2100], (5000, 2))
    theirs = np.array([fence.contains(p) for p in points])
    mine = _inside(fence_half_planes(FIELD), points)
    assert theirs.any()
    assert not theirs.all()
    assert np.array_equal(mine, theirs)


def test_a_paper_profile_has_no_fence() -> None:
    assert policy_config(builtin_profile("paper-fixed")).fence == ()


def test_a_concave_fence_is_refused_by_name() -> None:
    dart = [(0.0, 0.0), (100.0, 50.0), (0.0, 100.0), (30.0, 50.0)]
    with pytest.raises(ValueError, match=r"site\.geofence must be a convex polygon"):
        inset_half_planes(dart, 20.0)


@pytest.mark.parametrize("winding", [1, -1])
def test_the_inset_moves_every_edge_inwards_whatever_the_winding(winding: int) -> None:
    square = [(0.0, 0.0), (100.0, 0.0), (100.0, 100.0), (0.0, 100.0)][::winding]
    planes = inset_half_planes(square, 20.0)
    points = np.array([[50.0, 50.0], [21.0, 79.0], [19.0, 50.0], [50.0, 81.0], [-5.0, 50.0]])
    assert _inside(planes, points).tolist() == [True, True, False, False, False]


def test_redrawn_waypoints_stay_inside_the_inset_fence_where_unfenced_ones_leave_it() -> None:
    fenced = dataclasses.replace(policy_config(FIELD), out_of_area="redraw")
    assert fenced.fence
    planes = fenced.fence
    n = 4000
    outside = {}
    for name, config in (("fenced", fenced), ("area only", dataclasses.replace(fenced, fence=()))):
        policy = SearchPolicy(config)
        rng = np.random.default_rng(3)
        # positions inside the inset fence, many of them within 100 m of it
        pos = rng.uniform([60.0, 60.0], [1140.0, 1940.0], (n, 2))
        pos[: n // 2, 0] = rng.uniform(60.0, 160.0, n // 2)
        state = policy.start(pos, np.zeros(n), rng)
        drawn = [state.waypoint.copy()]
        for t in range(1, 4):
            obs = Observation(
                time=np.full(n, float(t)),
                position=pos,
                reached=np.ones(n, dtype=bool),
                contacts=np.zeros((n, 1), dtype=bool),
                contact_positions=np.zeros((n, 1, 2)),
            )
            policy.step(state, np.arange(n), obs, rng)
            drawn.append(state.waypoint.copy())
        every = np.concatenate(drawn)
        outside[name] = float(np.mean(~_inside(planes, every)))
    # only the rare fall-back after 16 redraws (mirrored into the area) may leave the fence
    assert outside["fenced"] < 0.002, outside
    assert outside["area only"] > 0.05, outside
