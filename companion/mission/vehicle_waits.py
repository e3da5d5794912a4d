"""The mission's waits in vehicle time: until a condition holds, a number of vehicle seconds
pass or the mission ends. The event intake calls :meth:`VehicleWaits.wake` after every change;
the waits are settled there rather than in their own tasks (a task woken for every position
only to wait again was one more event-loop iteration per position)."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable
from dataclasses import dataclass

from companion.mission.vehicle_clock import VehicleClock


@dataclass
class _Waiter:
    """One wait of :meth:`VehicleWaits.until`."""

    predicate: Callable[[], bool]
    start: float
    timeout: float | None
    future: asyncio.Future[bool]


class VehicleWaits:
    """Waits on ``clock``; ``ended()`` true ends every wait (False)."""

    def __init__(self, clock: VehicleClock, ended: Callable[[], bool]) -> None:
        self.clock = clock
        self.ended = ended
        self._changed = asyncio.Event()
        self._waiters: list[_Waiter] = []
        """:meth:`until`'s open waits, settled by :meth:`wake`."""

    async def wait_changed(self, timeout: float) -> None:
        """Until something changed (an event handled, a new state) or ``timeout`` wall s."""
        self._changed.clear()
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(self._changed.wait(), timeout)

    async def until(self, predicate: Callable[[], bool], timeout: float | None = None) -> bool:
        """Wait until ``predicate`` holds or ``timeout`` vehicle seconds pass (or the mission ends)."""
        waiter = _Waiter(
            predicate, self.clock.now, timeout, asyncio.get_running_loop().create_future()
        )
        settled = self._settled(waiter)
        if settled is not None:
            return settled
        self._waiters.append(waiter)
        try:
            return await waiter.future
        finally:
            self._waiters.remove(waiter)

    async def sleep_vehicle(self, seconds: float) -> None:
        """``seconds`` of vehicle time (or until the mission ends)."""
        start = self.clock.now
        await self.until(lambda: self.clock.now - start >= seconds)

    def wake(self) -> None:
        """Something changed: wake :meth:`wait_changed` and settle the waits of :meth:`until`."""
        self._changed.set()
        for w in self._waiters:
            if w.future.done():
                continue
            try:
                settled = self._settled(w)
            except Exception as exc:  # the waiting task gets it, as when it checked itself
                w.future.set_exception(exc)
                continue
            if settled is not None:
                w.future.set_result(settled)

    def _settled(self, w: _Waiter) -> bool | None:
        """True: ``w``'s predicate holds; False: timed out or the mission ended; None: wait on."""
        if w.predicate():
            return True
        if self.ended():
            return False
        if w.timeout is not None and self.clock.now - w.start >= w.timeout:
            return False
        return None
