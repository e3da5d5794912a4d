"""Waiting in tests for something another process or task does: one polling helper, in a
blocking and an asyncio form, that fails naming what was awaited and the last state seen."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from typing import TypeVar

S = TypeVar("S")

_SHOWN = 2000
"""Characters of the last state a failure shows (a trace or a log can be long)."""


def _timed_out(what: str, timeout: float, last: object, context: Callable[[], str] | None) -> str:
    shown = repr(last)
    if len(shown) > _SHOWN:
        shown = shown[:_SHOWN] + "..."
    more = "" if context is None else f"\n{context()}"
    return f"timed out after {timeout:g} s waiting for {what}; last seen: {shown}{more}"


def wait_until(
    observe: Callable[[], S],
    timeout: float,
    what: str,
    *,
    until: Callable[[S], object] = bool,
    every: float = 0.1,
    context: Callable[[], str] | None = None,
) -> S:
    """Call ``observe`` every ``every`` wall s until ``until(state)`` holds (by default: the
    state is true) and return that state. After ``timeout`` wall s: AssertionError naming
    ``what``, the last state and ``context()`` (e.g. a process's output)."""
    deadline = time.monotonic() + timeout
    while True:
        state = observe()
        if until(state):
            return state
        if time.monotonic() > deadline:
            raise AssertionError(_timed_out(what, timeout, state, context))
        time.sleep(every)


async def wait_until_async(
    observe: Callable[[], S],
    timeout: float,
    what: str,
    *,
    until: Callable[[S], object] = bool,
    every: float = 0.02,
    context: Callable[[], str] | None = None,
) -> S:
    """:func:`wait_until` inside an event loop: the loop runs the awaited tasks between looks."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    while True:
        state = observe()
        if until(state):
            return state
        if loop.time() > deadline:
            raise AssertionError(_timed_out(what, timeout, state, context))
        await asyncio.sleep(every)
