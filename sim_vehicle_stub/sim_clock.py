"""The simulation clock: sim seconds advance at ``speedup`` times wall time, or flat out."""

from __future__ import annotations

import time


class SimClock:
    """Tracks sim time and tells the stepping loop how long to wait for wall time to catch up."""

    def __init__(self, speedup: float | None, *, max_lag: float = 1.0) -> None:
        """``speedup`` None runs as fast as the machine allows; ``max_lag`` (wall s) is how far the
        loop may fall behind before the clock stops trying to catch up and re-bases."""
        if speedup is not None and speedup <= 0:
            raise ValueError(f"speedup must be > 0 (or None for max), got {speedup}")
        self.speedup = speedup
        self.max_lag = max_lag
        self.now = 0.0
        self.rebases = 0
        """How often the loop fell more than ``max_lag`` behind (sustained overload)."""
        self._wall0 = time.monotonic()
        self._sim0 = 0.0

    def restart(self) -> None:
        """Pace sim time from now on: what came before the loop started (loading the compiled
        kernels, about a second) is not lag for the loop to catch up by running fast."""
        self._wall0 = time.monotonic()
        self._sim0 = self.now

    def advance(self, dt: float) -> None:
        self.now += dt

    def wait_time(self) -> float:
        """Wall seconds to sleep before the next step (0 when behind or flat out)."""
        if self.speedup is None:
            return 0.0
        target = self._wall0 + (self.now - self._sim0) / self.speedup
        delay = target - time.monotonic()
        if delay < -self.max_lag:
            self.rebases += 1
            self._wall0 = time.monotonic()
            self._sim0 = self.now
            return 0.0
        return max(delay, 0.0)

    @property
    def boot_ms(self) -> int:
        return int(self.now * 1000.0)

    @property
    def usec(self) -> int:
        return int(self.now * 1e6)
