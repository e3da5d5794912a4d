"""Run many missions of a profile: blocks of runs in this process, local workers, or on Dask."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mdm_core import metrics
from mdm_montecarlo.engines.engine import BLOCK_RUNS, BlockResult, run_block
from mdm_montecarlo.engines.lawnmower_engine import LAWNMOWER_KINDS, run_lawnmower_block
from mdm_montecarlo.engines.local_pool import imap_unordered
from mdm_montecarlo.engines.social_engine import SWARM_KINDS, run_swarm_block
from mdm_montecarlo.errors import MontecarloError
from mdm_profiles import MissionProfile

Progress = Callable[[int], None]


@dataclass(frozen=True)
class MissionResults:
    """Per-run outcomes of a batch of missions of one profile."""

    profile: MissionProfile
    seed: int
    team_times: NDArray[np.float64]
    """(runs, targets) earliest confirmation of each target by any vehicle; inf if never."""
    first_vehicle: NDArray[np.int64]
    """(runs, targets) the vehicle (0-based) that made that earliest confirmation; -1 if none."""
    run_block: NDArray[np.int64]
    """(runs,) the block of each run: its random streams are SeedSequence([seed, block])."""
    run_in_block: NDArray[np.int64]
    """(runs,) each run's place in its block (its lanes' rows in the block's streams)."""
    events: int
    sim_seconds: float
    followed: int | None = None
    """Swarm baselines: particle-iterations that followed a peer's best (of ``events``)."""
    gone: NDArray[np.float64] | None = None
    """(runs, targets) when each target left the area, where T_S counts it
    (``mission.ts_rule: confirmed_or_gone``); else None."""

    @property
    def runs(self) -> int:
        return len(self.team_times)

    @property
    def follow_share(self) -> float | None:
        """Share of the swarm's particle-iterations that followed a best heard from a peer."""
        return None if self.followed is None else self.followed / max(self.events, 1)

    @property
    def real(self) -> NDArray[np.bool_]:
        return np.array([not t.false_target for t in self.profile.targets])

    @property
    def tnc(self) -> NDArray[np.int64]:
        """T_nc of every run at the profile's mission duration."""
        return metrics.confirmed_within(self.team_times, self.profile.mission.duration)

    @property
    def has_ts(self) -> bool:
        """False where runs stopped at the mission duration (ts_cap <= duration): T_nc only.

        reproduce does that for the swarm baselines, for which the paper prints no T_S.
        """
        mission = self.profile.mission
        return mission.ts_cap > mission.duration

    def ts(self) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """T_S of every run (capped at mission.ts_cap) and which runs were capped."""
        return metrics.time_to_all(
            self.team_times, self.real, self.profile.mission.ts_cap, self.gone
        )


class RunInterruptedError(MontecarloError):
    """Ctrl-C during ``run_many``: the workers are stopped; ``finished`` holds the profiles
    (by index) all of whose blocks were done, ``partial`` those with only some blocks done
    (their results cover fewer runs than asked)."""

    def __init__(
        self, finished: dict[int, MissionResults], partial: dict[int, MissionResults]
    ) -> None:
        super().__init__("interrupted")
        self.finished = finished
        self.partial = partial


def is_swarm(profile: MissionProfile) -> bool:
    """Whether the profile's rows run on the time-stepped swarm engine (PSO/SPSO/ARPSO)."""
    return profile.policy.kind in SWARM_KINDS


def simulate_block(profile: MissionProfile, seed: int, block: int, n_runs: int) -> BlockResult:
    """One block of runs: the event-driven engine, the time-stepped one for PSO/SPSO/ARPSO, or
    the lawnmowers' (LM1/LM2)."""
    if is_swarm(profile):
        return run_swarm_block(profile, seed, block, n_runs)
    if profile.policy.kind in LAWNMOWER_KINDS:
        return run_lawnmower_block(profile, seed, block, n_runs)
    return run_block(profile, seed, block, n_runs)


def _indexed_block(
    index: int, profile: MissionProfile, seed: int, block: int, n_runs: int
) -> tuple[int, BlockResult]:
    """simulate_block tagged with the profile's index (local workers return in any order)."""
    return index, simulate_block(profile, seed, block, n_runs)


def _relative_cost(profile: MissionProfile) -> float:
    """Rough CPU cost of one run (ordering only): swarms step every update interval; moving
    targets cost about twice fixed ones."""
    mission = profile.mission
    if is_swarm(profile):
        return 4.0 * mission.duration / 1000.0
    return 2.0 if profile.target_motion is not None else 1.0


def job_order(
    profiles: list[MissionProfile], runs: int, block_runs: int, workers: int
) -> list[tuple[int, int, int]]:
    """The (profile index, block, runs) jobs of :func:`run_many` in the order they are handed
    out: longest first, so no worker is left alone with a long block at the end; then the
    first job of each engine (swarm, batch) moved to the front, one per worker.

    A worker compiles the numba kernels of the engine it runs; where none are cached yet (the
    first run after an install) workers that all start on the same engine each compile both
    engines' kernels (about 7 CPU-s swarm, 15 batch), instead of one engine each while the
    other's kernels are cached for it. The order changes no result: each block's random
    stream is its own."""
    jobs = [(i, b, n) for i in range(len(profiles)) for b, n in _blocks(runs, block_runs)]
    jobs.sort(key=lambda job: _relative_cost(profiles[job[0]]) * job[2], reverse=True)
    firsts: dict[bool, int] = {}
    for k, (i, _, _) in enumerate(jobs):
        firsts.setdefault(is_swarm(profiles[i]), k)
    front = sorted(firsts.values())[: max(workers, 1)]
    return [jobs[k] for k in front] + [job for k, job in enumerate(jobs) if k not in front]


def _blocks(runs: int, block_runs: int) -> Iterator[tuple[int, int]]:
    for b, first in enumerate(range(0, runs, block_runs)):
        yield b, min(block_runs, runs - first)


def run_missions(
    profile: MissionProfile,
    *,
    runs: int,
    seed: int = 0,
    workers: int = 1,
    scheduler: str | None = None,
    progress: Progress | None = None,
    block_runs: int = BLOCK_RUNS,
) -> MissionResults:
    """Simulate ``runs`` missions. Identical results for any ``workers`` or a Dask ``scheduler``.

    workers: local processes (1 = this process). scheduler: address of a Dask distributed
    scheduler (e.g. 'tcp://127.0.0.1:8786'); when given, blocks are computed there instead.
    """
    return run_many(
        [profile],
        runs=runs,
        seed=seed,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        block_runs=block_runs,
    )[0]


def run_many(
    profiles: list[MissionProfile],
    *,
    runs: int,
    seed: int = 0,
    workers: int = 1,
    scheduler: str | None = None,
    progress: Progress | None = None,
    block_runs: int = BLOCK_RUNS,
    meanwhile: Callable[[], object] | None = None,
) -> list[MissionResults]:
    """``run_missions`` for several profiles at once, sharing one pool (or Dask client).

    ``meanwhile`` is called once in this process while the runs compute elsewhere (local
    workers or Dask), never with ``workers=1`` and no scheduler.
    """
    if runs < 1:
        raise ValueError(f"runs must be >= 1, got {runs}")
    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    jobs = job_order(profiles, runs, block_runs, workers)
    blocks: dict[int, list[BlockResult]] = {i: [] for i in range(len(profiles))}
    expected = {i: sum(1 for job in jobs if job[0] == i) for i in range(len(profiles))}
    done = progress or (lambda _n: None)
    try:
        _run_jobs(profiles, jobs, seed, workers, scheduler, blocks, done, meanwhile)
    except KeyboardInterrupt:
        finished = {
            i: _collect(profiles[i], seed, got)
            for i, got in blocks.items()
            if got and len(got) == expected[i]
        }
        partial = {
            i: _collect(profiles[i], seed, got)
            for i, got in blocks.items()
            if got and len(got) < expected[i]
        }
        raise RunInterruptedError(finished, partial) from None
    return [_collect(profiles[i], seed, blocks[i]) for i in range(len(profiles))]


def _run_jobs(
    profiles: list[MissionProfile],
    jobs: list[tuple[int, int, int]],
    seed: int,
    workers: int,
    scheduler: str | None,
    blocks: dict[int, list[BlockResult]],
    done: Progress,
    meanwhile: Callable[[], object] | None,
) -> None:
    """Compute every (profile, block, runs) job into ``blocks`` (in place)."""
    if scheduler is not None:
        from distributed import Client
        from distributed import as_completed as dask_completed

        with Client(scheduler) as client:  # type: ignore[no-untyped-call]
            futures = {
                client.submit(simulate_block, profiles[i], seed, b, n, pure=False): i
                for i, b, n in jobs
            }
            if meanwhile is not None:
                meanwhile()
            for fut in dask_completed(futures):  # type: ignore[no-untyped-call]
                blocks[futures[fut]].append(fut.result())
                done(blocks[futures[fut]][-1].per_vehicle.shape[0])
    elif workers > 1:
        _load_kernels([profiles[i] for i, _, _ in jobs])
        work = [(i, profiles[i], seed, b, n) for i, b, n in jobs]
        for i, result in imap_unordered(_indexed_block, work, workers, meanwhile):
            blocks[i].append(result)
            done(result.per_vehicle.shape[0])
    else:
        for i, b, n in jobs:
            blocks[i].append(simulate_block(profiles[i], seed, b, n))
            done(n)


def _load_kernels(profiles: list[MissionProfile]) -> None:
    """One run of the first profile of each engine (batch, interval swarm, waypoint swarm),
    here, thrown away: numba loads an engine's cached kernels on its first call (about 0.45
    CPU-s for the three), so the workers forked after this share them instead of each loading
    its own. The run's streams are its own (block 0 of seed 0); no result depends on it."""
    firsts = {_engine(p): p for p in reversed(profiles)}
    for profile in firsts.values():
        simulate_block(profile, 0, 0, 1)


def _engine(profile: MissionProfile) -> str:
    return profile.policy.swarm.iteration if is_swarm(profile) else "batch"


def _collect(profile: MissionProfile, seed: int, results: list[BlockResult]) -> MissionResults:
    results = sorted(results, key=lambda r: r.first_block)
    per_vehicle = np.concatenate([r.per_vehicle for r in results], axis=0)
    team = metrics.team_times(per_vehicle)
    sizes = [r.per_vehicle.shape[0] for r in results]
    return MissionResults(
        profile=profile,
        seed=seed,
        team_times=team,
        first_vehicle=np.where(np.isfinite(team), per_vehicle.argmin(axis=1), -1),
        run_block=np.repeat([r.first_block for r in results], sizes).astype(np.int64),
        run_in_block=np.concatenate([np.arange(n, dtype=np.int64) for n in sizes]),
        events=sum(r.events for r in results),
        sim_seconds=sum(r.sim_seconds for r in results),
        followed=None
        if any(r.followed is None for r in results)
        else sum(r.followed or 0 for r in results),
        gone=None
        if any(r.gone is None for r in results)
        else np.concatenate([r.gone for r in results if r.gone is not None], axis=0),
    )
