"""The engine's kernels compile whether or not numba can cache them on disk."""

from __future__ import annotations

from typing import Any

import numpy as np

from mdm_core.jit import compiled


def _without_source_file() -> Any:
    """A function numba cannot locate a cache for (its source is no file): as in a read-only
    install with a read-only home, where ``njit(cache=True)`` raises at decoration."""
    namespace: dict[str, Any] = {}
    code = "def double_sum(x):\n    s = 0.0\n    for v in x:\n        s += 2.0 * v\n    return s\n"
    exec(compile(code, "<generated>", "exec"), namespace)
    return namespace["double_sum"]


def test_a_kernel_without_a_cache_location_still_compiles_and_runs() -> None:
    kernel = compiled(_without_source_file())
    assert kernel(np.arange(4.0)) == 12.0
    assert kernel.signatures  # compiled by numba, not the Python function handed back


def _ratio(a: float, b: float) -> float:
    return a / b


def test_a_division_by_zero_gives_what_numpy_gives() -> None:
    kernel = compiled(_ratio)
    assert kernel(1.0, 0.0) == np.inf
    assert np.isnan(kernel(0.0, 0.0))
    assert kernel(-1.0, 0.0) == -np.inf
