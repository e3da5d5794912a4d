"""The compiled entry kernel answers bit for bit as numpy's closed form, piece by piece."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from mdm_core.world import Scenario, TargetTracks, first_entry_time
from mdm_montecarlo.kernels.entry_kernel import entry_row
from mdm_profiles import builtin_profile

RUNS = 200
LANES = 3000


@dataclass(frozen=True)
class Leg:
    """Straight flight of each lane: start, velocity, seconds."""

    start: np.ndarray
    velocity: np.ndarray
    duration: np.ndarray


def _piecewise(
    tracks: TargetTracks,
    runs: np.ndarray,
    t: np.ndarray,
    leg: Leg,
    radius: np.ndarray,
    eligible: np.ndarray,
    appear: np.ndarray,
) -> np.ndarray:
    """The oracle: first_entry_time on each piece between grid nodes, in numpy, until a piece
    holds a contact or the leg ends."""
    out = np.full(eligible.shape, np.inf)
    begin = np.zeros(len(t))
    rows = np.arange(len(t))
    while rows.size:
        now = t[rows] + begin[rows]
        position, velocity = tracks.motion(runs[rows], now)
        end = np.minimum(tracks.next_node_time(now) - t[rows], leg.duration[rows])
        piece = first_entry_time(
            leg.start[rows] + leg.velocity[rows] * begin[rows, None],
            leg.velocity[rows],
            end - begin[rows],
            position,
            velocity,
            radius[rows],
            eligible[rows],
            appear - now[:, None],
            tracks.max_speed,
        )
        out[rows] = piece + begin[rows, None]
        more = ~np.isfinite(piece).any(axis=1) & (end < leg.duration[rows])
        begin[rows[more]] = end[more]
        rows = rows[more]
    return out


@pytest.mark.parametrize("profile_name", ["paper-fixed", "paper-popup", "paper-dynamic"])
def test_kernel_equals_the_numpy_closed_form_on_random_legs(profile_name: str) -> None:
    profile = builtin_profile(profile_name)
    scenario = Scenario.from_profile(profile)
    rng = np.random.default_rng(11)
    tracks = scenario.tracks(RUNS, rng)
    size = scenario.area.size
    m = scenario.targets.count
    runs = rng.integers(0, RUNS, LANES)
    t = rng.uniform(0.0, 1500.0, LANES)
    heading = rng.uniform(0.0, 2 * np.pi, LANES)
    speed = profile.fleet.speed
    velocity = speed * np.stack([np.cos(heading), np.sin(heading)], axis=1)
    # Legs from a few seconds to several grid cells; some of zero length.
    duration = rng.choice([0.0, 3.0, 25.0, 90.0, 400.0], LANES)
    leg = Leg(rng.uniform(0.0, 1.0, (LANES, 2)) * size, velocity, duration)
    radius = rng.choice([r.radius for r in scenario.sensors], LANES)
    eligible = rng.random((LANES, m)) < 0.8
    appear = scenario.targets.appear_times

    seg_start, seg_velocity = tracks.segments(float(np.max(t + leg.duration)))
    got = np.empty(eligible.shape)
    for i in range(LANES):
        entry_row(
            leg.start[i, 0],
            leg.start[i, 1],
            leg.velocity[i, 0],
            leg.velocity[i, 1],
            leg.duration[i],
            t[i],
            runs[i] if tracks.moving else 0,
            radius[i],
            eligible,
            i,
            appear,
            seg_start,
            seg_velocity,
            tracks.grid_dt,
            tracks.max_speed,
            tracks.moving,
            got[i],
        )
    expected = _piecewise(tracks, runs, t, leg, radius, eligible, appear)

    np.testing.assert_array_equal(got, expected)
    hits = np.isfinite(expected)
    # Enough contacts, and on moving targets beyond the first piece, that a wrong kernel shows.
    assert hits.sum() > 100
    assert not hits[~eligible].any()
    if tracks.moving:
        past_a_node = expected > (tracks.next_node_time(t) - t)[:, None]
        assert past_a_node[hits].sum() > 50
