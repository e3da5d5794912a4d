"""numba's compiler for the project's kernels (the Monte-Carlo engine's, the emulator's fleet
step): cached on disk where a cache can be written.

``njit(cache=True)`` raises at import when no cache folder is writable (a read-only install
with a read-only home, say); the kernels are then compiled once per process instead (about
15 s for all of them on the project's machine, most of it the policy's random draws) rather
than the engine failing to import.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Literal, TypeVar, cast

from numba import njit

F = TypeVar("F", bound=Callable[..., Any])


def compiled(fn: F, *, nogil: bool = True, error_model: Literal["python", "numpy"] = "python") -> F:
    """``fn`` compiled in nopython mode, cached on disk if possible; with the GIL released
    unless ``nogil`` is False (a kernel updating state that other threads read whole).
    ``error_model="numpy"``: a float division by zero gives inf or NaN, as in numpy, instead of
    raising ZeroDivisionError."""
    try:
        return cast(F, njit(cache=True, nogil=nogil, error_model=error_model)(fn))
    except RuntimeError:  # "cannot cache function ...: no locator available"
        return cast(F, njit(nogil=nogil, error_model=error_model)(fn))
