"""The companion's lawnmower core (companion.mission.lawnmower_core) flies the engine's rules:
stepped as a point mass against the world's targets (contacts as the emulator reports them:
every target inside the active sensor's disc, a confirming sensor blind to false targets), its
confirmations are the compiled engine's (mdm_montecarlo.kernels.lawnmower_kernel) for the same
start points, plan and targets; and its lanes are the plan's, cut to the guidance fence."""

from __future__ import annotations

import math

import numpy as np
import pytest

from companion.fence_from_profile import guidance_fence
from companion.geofence import Geofence
from companion.mission.fenced_lanes import fenced_lanes
from companion.mission.lawnmower_core import LawnmowerCore
from mdm_core.search.lawnmower_profile import team_plan
from mdm_core.world.scenario import Scenario
from mdm_montecarlo.engines.lawnmower_engine import fly_planned
from mdm_montecarlo.study.variants import with_method
from mdm_profiles import MissionProfile, builtin_profile
from mdm_profiles.overrides import apply_overrides

SEED = 5
DT = 0.05
"""Step, s: 0.5 m at the site's 10 m/s."""
TOLERANCE = {"LM1": DT + 1e-6, "LM2": 10 * DT}
"""As the engine's own test against its stepped reference (tests/montecarlo/
test_lawnmower_engine.py): only the sensor reads are quantised (LM1), and LM2's point of
detection by up to speed x dt, which moves the whole search."""


def _profile(method: str, scenario: str) -> MissionProfile:
    """field-duebendorf without its site (the guidance fence is the area: the plan's lanes
    unchanged), lanes overlapping 10 % (as the engine's test), a false target; pop-up targets
    appearing at 150 s intervals. Its first target moved 10 m north: at north 300 m it lies
    exactly r1 from the area's south edge, where a transit along that edge is tangent to its
    detection disc (the engine's closed form counts the touch, a stepped flight does not)."""
    base = builtin_profile("field-duebendorf").model_copy(update={"site": None})
    changes = ["policy.lawnmower.overlap=0.1", "targets.0.north=310"]
    profile = apply_overrides(with_method(base, method), changes)
    if scenario == "popup":
        profile = apply_overrides(
            profile, [f"targets.{k}.appear={150 * (k + 1)}" for k in range(4)]
        )
    return profile


def _fly_core(core: LawnmowerCore, profile: MissionProfile, start: np.ndarray) -> np.ndarray:
    """First confirmation time of each target (inf: never) by ``core`` flown as a point mass
    from ``start`` at the fleet speed, its sensor read at the end of every step."""
    scenario = Scenario.from_profile(profile)
    where = scenario.targets.positions
    real = ~scenario.targets.false_mask
    appear = scenario.targets.appear_times
    radii = [s.radius for s in profile.sensors]
    first = np.full(len(where), np.inf)
    pos = np.asarray(start, dtype=float).copy()
    core.start(pos, 0.0, [])
    cap = max(profile.mission.ts_cap, profile.mission.duration)
    t = 0.0
    while t < cap - 1e-9:
        budget = profile.fleet.speed * DT
        while budget > 0:
            goal = core.waypoint
            gap = float(np.hypot(*(goal - pos)))
            if gap > budget:
                pos = pos + (goal - pos) / gap * budget
                break
            pos, budget = goal.copy(), budget - gap
            core.step(t, pos, True, np.zeros((0, 2)))
        t += DT
        sensor = core.sensor()
        confirms = sensor == len(radii) - 1
        seen = (appear <= t) & (np.hypot(*(where - pos).T) < radii[sensor])
        if confirms:
            seen &= real
        contacts = where[seen]
        if core.needs_step(t, pos, False, contacts):
            for north, east in core.step(t, pos, False, contacts).confirmed:
                k = int(np.argmin(np.hypot(where[:, 0] - north, where[:, 1] - east)))
                first[k] = min(first[k], t)
        if t >= profile.mission.duration and np.isfinite(first[real]).all():
            break
    return first


def _engine(profile: MissionProfile, starts: np.ndarray) -> np.ndarray:
    """The compiled engine's first confirmations (vehicles, targets) for these start points."""
    scenario = Scenario.from_profile(profile)
    cap = max(profile.mission.ts_cap, profile.mission.duration)
    tracks = scenario.tracks(1, np.random.default_rng(0))
    first, _, _ = fly_planned(profile, scenario, tracks, starts[np.newaxis], cap)
    return first


@pytest.mark.parametrize("scenario", ["fixed", "popup"])
@pytest.mark.parametrize("method", ["LM1", "LM2"])
def test_the_core_confirms_what_the_engine_confirms(method: str, scenario: str) -> None:
    profile = _profile(method, scenario)
    n = profile.fleet.vehicles
    starts, _ = Scenario.from_profile(profile).live_run(SEED, n, profile.fleet.start)
    fence = Geofence.rectangle(profile.area.north, profile.area.east)
    engine = _engine(profile, starts)
    core = np.stack(
        [_fly_core(LawnmowerCore(profile, SEED, i, fence), profile, starts[i]) for i in range(n)]
    )
    real = np.array([not t.false_target for t in profile.targets])
    assert np.isfinite(engine[:, real]).any(axis=0).all(), "the team confirms every real target"
    assert not np.isfinite(core[:, ~real]).any(), "a false target confirmed"
    np.testing.assert_array_equal(np.isfinite(core), np.isfinite(engine))
    done = np.isfinite(engine)
    gap = float(np.abs(core[done] - engine[done]).max())
    assert gap <= TOLERANCE[method], f"{method} {scenario}: {gap:.3f} s"


@pytest.mark.parametrize("method", ["LM1", "LM2"])
def test_lanes_are_the_plans_cut_to_the_guidance_fence(method: str) -> None:
    profile = with_method(builtin_profile("field-duebendorf"), method)
    fence = guidance_fence(profile)
    n = profile.fleet.vehicles
    starts, _ = Scenario.from_profile(profile).live_run(SEED, n, profile.fleet.start)
    plan = team_plan(profile, starts)
    axis = plan.grid.axis
    for i in range(n):
        lanes = LawnmowerCore(profile, SEED, i, fence).lanes
        planned = plan.waypoints[i]
        assert all(fence.contains(p) for p in lanes), f"vehicle {i}: a lane end outside"
        assert 0 < len(lanes) <= len(planned)
        assert len(lanes) % 2 == 0
        crosses = {round(float(p[1 - axis]), 6) for p in planned}
        for a, b in zip(lanes[::2], lanes[1::2], strict=True):
            assert a[1 - axis] == pytest.approx(b[1 - axis])  # a lane along the plan's axis
            assert round(float(a[1 - axis]), 6) in crosses  # ... on one of the plan's lanes
            # ... from fence to fence: its ends on the fence or on the cell's edge
            for p in (a, b):
                on_edge = min(abs(p[axis] - plan.regions[i, 0, axis]),
                              abs(p[axis] - plan.regions[i, 1, axis]))  # fmt: skip
                assert min(fence.distance(*p), on_edge) < 1e-6


def test_a_cell_outside_the_fence_is_refused() -> None:
    sweep = np.array([[0.0, 0.0], [0.0, 100.0], [10.0, 100.0], [10.0, 0.0]])
    fence = Geofence(np.array([[50.0, 0.0], [100.0, 0.0], [100.0, 100.0], [50.0, 100.0]]))
    with pytest.raises(ValueError, match="no lane of this vehicle's cell lies inside"):
        fenced_lanes(sweep, fence)
    inside = fenced_lanes(sweep + np.array([60.0, -20.0]), fence)
    np.testing.assert_allclose(inside, [[60, 0], [60, 80], [70, 80], [70, 0]])
    assert math.isclose(float(np.hypot(*(inside[1] - inside[0]))), 80.0)
    # the first lane dropped: the next ones turned round, the sweep still starts at the corner
    three = np.vstack([sweep, [[20.0, 0.0], [20.0, 100.0]]]) + np.array([40.0, 0.0])
    np.testing.assert_allclose(fenced_lanes(three, fence), [[50, 0], [50, 100], [60, 100], [60, 0]])
