"""run_missions is a function of (profile, runs, seed, block_runs): same seed -> same bits.

120 runs in blocks of 50 gives three blocks of unequal size (50, 50, 20), so the checks cover
the seeding per block and the reassembly of blocks that finish in any order. The T_S cap is
lowered to the mission duration so that runs end at 1000 s (bit-identity does not depend on it).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
from distributed import LocalCluster

from mdm_montecarlo.engines.runner import MissionResults, job_order, run_many, run_missions
from mdm_montecarlo.study.variants import with_method
from mdm_profiles import MissionProfile, load_profile

RUNS = 120
BLOCK_RUNS = 50
SEED = 11


@pytest.fixture(scope="module")
def profile() -> MissionProfile:
    base = load_profile("paper-fixed")
    mission = base.mission.model_copy(update={"ts_cap": base.mission.duration})
    return base.model_copy(update={"mission": mission})


@pytest.fixture(scope="module")
def serial(profile: MissionProfile) -> MissionResults:
    return run_missions(profile, runs=RUNS, seed=SEED, workers=1, block_runs=BLOCK_RUNS)


@pytest.fixture(scope="module")
def cluster() -> Iterator[LocalCluster]:
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as c:  # type: ignore[no-untyped-call]
        yield c


def test_shape_and_content(serial: MissionResults, profile: MissionProfile) -> None:
    assert serial.team_times.shape == (RUNS, len(profile.targets))
    assert serial.runs == RUNS
    # Not a degenerate result: some targets confirmed, and not the same count in every run.
    assert np.isfinite(serial.team_times).any()
    assert len(np.unique(serial.tnc)) > 1


def test_same_seed_twice_is_identical(serial: MissionResults, profile: MissionProfile) -> None:
    again = run_missions(profile, runs=RUNS, seed=SEED, workers=1, block_runs=BLOCK_RUNS)
    assert np.array_equal(serial.team_times, again.team_times)
    assert serial.events == again.events


def test_two_local_workers_match_one(serial: MissionResults, profile: MissionProfile) -> None:
    pooled = run_missions(profile, runs=RUNS, seed=SEED, workers=2, block_runs=BLOCK_RUNS)
    assert np.array_equal(serial.team_times, pooled.team_times)
    assert serial.events == pooled.events


def test_dask_cluster_matches_one_worker(
    serial: MissionResults, profile: MissionProfile, cluster: LocalCluster
) -> None:
    remote = run_missions(
        profile,
        runs=RUNS,
        seed=SEED,
        scheduler=cluster.scheduler_address,
        block_runs=BLOCK_RUNS,
    )
    assert np.array_equal(serial.team_times, remote.team_times)
    assert serial.events == remote.events


def test_different_seed_differs(serial: MissionResults, profile: MissionProfile) -> None:
    other = run_missions(profile, runs=RUNS, seed=SEED + 1, workers=1, block_runs=BLOCK_RUNS)
    assert other.team_times.shape == serial.team_times.shape
    assert not np.array_equal(serial.team_times, other.team_times)


def test_block_prefix_is_stable(serial: MissionResults, profile: MissionProfile) -> None:
    # Block b depends only on (seed, b): the first two blocks of a shorter batch are the same runs.
    short = run_missions(profile, runs=2 * BLOCK_RUNS, seed=SEED, block_runs=BLOCK_RUNS)
    assert np.array_equal(short.team_times, serial.team_times[: 2 * BLOCK_RUNS])


def test_the_first_jobs_of_a_pool_are_one_per_engine_and_change_no_result(
    profile: MissionProfile,
) -> None:
    """Sorted longest first, the swarm rows' jobs all come before the batch engine's: a pool
    whose workers all started on them would compile both engines' kernels in every worker on
    a fresh install. One job per engine goes first instead, and results stay the same."""
    swarm = with_method(profile, "PSO")
    profiles = [profile, swarm, swarm]
    jobs = job_order(profiles, 80, 40, 2)
    assert sorted(jobs) == [(i, b, 40) for i in (0, 1, 2) for b in (0, 1)]
    assert [i for i, _, _ in jobs] == [1, 0, 1, 2, 2, 0]
    assert [i for i, _, _ in job_order(profiles, 80, 40, 1)] == [1, 1, 2, 2, 0, 0]
    alone = [run_missions(p, runs=RUNS, seed=SEED, block_runs=BLOCK_RUNS) for p in profiles[:2]]
    pooled = run_many(profiles[:2], runs=RUNS, seed=SEED, workers=2, block_runs=BLOCK_RUNS)
    for one, many in zip(alone, pooled, strict=True):
        assert np.array_equal(one.team_times, many.team_times)
        assert one.events == many.events
