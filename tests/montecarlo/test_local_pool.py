"""mdm_montecarlo.engines.local_pool: every job's result once, errors raised in the parent, workers
gone after the iterator is closed (as on Ctrl-C)."""

from __future__ import annotations

import gc
import multiprocessing
import os

import pytest

from mdm_montecarlo.engines.local_pool import imap_unordered


def _square(x: int) -> tuple[int, int]:
    return x * x, os.getpid()


def _fail(x: int) -> int:
    raise ValueError(f"bad job {x}")


def _frozen(_x: int) -> int:
    return gc.get_freeze_count()


def test_every_job_once_from_several_processes() -> None:
    out = list(imap_unordered(_square, [(x,) for x in range(20)], workers=3))
    assert sorted(v for v, _ in out) == [x * x for x in range(20)]
    assert len({pid for _, pid in out}) > 1
    assert os.getpid() not in {pid for _, pid in out}


def test_an_error_in_a_job_is_raised_in_the_parent() -> None:
    with pytest.raises(ValueError, match="bad job"):
        list(imap_unordered(_fail, [(1,), (2,)], workers=2))


def test_closing_early_stops_the_workers() -> None:
    results = imap_unordered(_square, [(x,) for x in range(50)], workers=2)
    _, pid = next(results)
    results.close()
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)


def test_started_is_called_here_once_every_worker_has_its_job() -> None:
    before = len(multiprocessing.active_children())
    seen: list[int] = []
    jobs = [(x,) for x in range(6)]

    def started() -> None:
        seen.append(len(multiprocessing.active_children()) - before)

    out = list(imap_unordered(_square, jobs, workers=2, started=started))
    assert sorted(v for v, _ in out) == [x * x for x in range(6)]
    assert seen == [2]


def test_workers_inherit_this_process_objects_frozen_and_it_unfreezes_them() -> None:
    before = gc.get_freeze_count()
    (frozen,) = imap_unordered(_frozen, [(0,)], workers=1)
    assert frozen > before
    assert gc.get_freeze_count() == before
