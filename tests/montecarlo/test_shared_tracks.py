"""Moving targets' paths drawn once per thread and shared by the blocks that ask for the same
ones (mdm_montecarlo.kernels.compiled_tracks.shared_tracks): the same object for the same targets, runs
and stream, and the same results as paths drawn afresh, also when an earlier configuration has
grown them further than this one needs."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from mdm_core.world import Scenario, TargetTracks
from mdm_montecarlo.engines.engine import block_rngs
from mdm_montecarlo.engines.runner import simulate_block
from mdm_montecarlo.kernels.compiled_tracks import shared_tracks
from mdm_montecarlo.study.cases import Case
from mdm_profiles.overrides import apply_overrides

SEED = 918_273  # no other test draws this stream: the first block here draws fresh paths


def _tracks(seed: int, block: int, runs: int, scenario: str = "dynamic") -> TargetTracks:
    profile = Case(scenario, "MDM", 20.0, 12, 0).profile()
    return shared_tracks(Scenario.from_profile(profile), runs, block_rngs(seed, block)[0], 1000.0)


def test_the_same_paths_are_one_object_and_other_paths_are_not() -> None:
    first = _tracks(SEED + 1, 0, 20)
    assert _tracks(SEED + 1, 0, 20) is first
    assert _tracks(SEED + 1, 1, 20) is not first  # another block's stream
    assert _tracks(SEED + 1, 0, 21) is not first  # another number of runs
    fixed = _tracks(SEED + 1, 0, 20, "fixed")
    assert not fixed.moving
    assert _tracks(SEED + 1, 0, 20, "fixed") is not fixed  # fixed targets are not kept


def test_each_thread_draws_its_own() -> None:
    mine = _tracks(SEED + 2, 0, 20)
    theirs: list[object] = []
    worker = threading.Thread(target=lambda: theirs.append(_tracks(SEED + 2, 0, 20)))
    worker.start()
    worker.join()
    assert theirs[0] is not mine
    assert _tracks(SEED + 2, 0, 20) is mine


@pytest.mark.parametrize(
    ("method", "seed"),
    [("MDM", SEED + 11), ("PSO", SEED + 12), ("SPSO", SEED + 13)],
    ids=["batch", "waypoint swarm", "interval swarm"],
)
def test_results_with_paths_grown_by_another_configuration_are_those_of_fresh_paths(
    method: str, seed: int
) -> None:
    """Each case has a stream of its own, so its first block draws fresh paths."""
    # Each to the mission duration (1000 s) only.
    settings = ["policy.swarm.iteration=interval"] if method == "SPSO" else []
    settings += ["mission.ts_cap=1000"] if method == "MDM" else []
    profile = apply_overrides(Case("dynamic", method, 20.0, 12, 0).profile(), settings)
    # T_S to 40 000 s: this configuration grows the shared paths far past the first one's.
    longer = Case("dynamic", "MDM:LS+BS", 20.0, 12, 0).profile()
    fresh = simulate_block(profile, seed, 3, 40)
    tracks = _tracks(seed, 3, 40)
    reach = tracks.filled
    simulate_block(longer, seed, 3, 40)
    assert tracks.filled > reach  # the paths were grown further
    again = simulate_block(profile, seed, 3, 40)
    assert _tracks(seed, 3, 40) is tracks
    assert np.array_equal(fresh.per_vehicle, again.per_vehicle)
    assert (fresh.events, fresh.sim_seconds, fresh.followed) == (
        again.events,
        again.sim_seconds,
        again.followed,
    )
    assert np.isfinite(fresh.per_vehicle).any()
