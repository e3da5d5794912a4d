"""mdm_montecarlo.local_pool: every job's result once, errors raised in the parent, workers
gone after the iterator is closed (as on Ctrl-C)."""

from __future__ import annotations

import os

import pytest

from mdm_montecarlo.local_pool import imap_unordered


def _square(x: int) -> tuple[int, int]:
    return x * x, os.getpid()


def _fail(x: int) -> int:
    raise ValueError(f"bad job {x}")


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
