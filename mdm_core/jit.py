"""numba's compiler for the project's kernels (the Monte-Carlo engine's, the emulator's fleet
step): cached on disk where a cache can be written.

``njit(cache=True)`` raises at import when no cache folder is writable (a read-only install
with a read-only home, say); the kernels are then compiled once per process instead (about
15 s for all of them on the project's machine, most of it the policy's random draws) rather
than the engine failing to import.

Every kernel uses numba's numpy error model: a float division by zero gives inf or NaN, as in
the numpy code each kernel replaces, instead of raising ZeroDivisionError. The Python model
tests every divisor before dividing; without those tests the engine's kernels take about 8 %
less CPU (docs/model.md, "Speed of reproduce"), with the same results wherever no division by
zero happens (where one does, the Python model would have raised).

A kernel taking a NamedTuple (the Monte-Carlo engine's structures) has that class named by
module and name in its cache index: once the class moves to another module, a cache written
before fails to load (ModuleNotFoundError at the kernel's first call) until the stale
``__pycache__`` folder is deleted.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Literal, TypeVar, cast

from numba import njit

F = TypeVar("F", bound=Callable[..., Any])


def compiled(fn: F, *, nogil: bool = True, inline: bool = False) -> F:
    """``fn`` compiled in nopython mode with numpy's error model, cached on disk if possible;
    with the GIL released unless ``nogil`` is False (a kernel updating state that other threads
    read whole). ``inline``: compiled into each kernel that calls it instead of called (a
    kernel called once per lane, whose call would cost more than its arithmetic)."""
    mode: Literal["never", "always"] = "always" if inline else "never"
    try:
        return cast(F, njit(cache=True, nogil=nogil, error_model="numpy", inline=mode)(fn))
    except RuntimeError:  # "cannot cache function ...: no locator available"
        return cast(F, njit(nogil=nogil, error_model="numpy", inline=mode)(fn))
