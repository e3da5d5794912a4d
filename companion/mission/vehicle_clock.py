"""Mission time from the vehicle's clock: monotonic across vehicle reboots and companion restarts."""

from __future__ import annotations

import logging

log = logging.getLogger(__name__)


class VehicleClock:
    """Vehicle seconds (time_boot_ms / 1000) made monotonic.

    A vehicle that reboots (an emulator restarted) starts its clock again near 0; the jump
    back is absorbed into an offset so C_I decay and mission duration keep counting. ``floor``
    is the last time a previous run of this companion logged, so a restart continues from it.
    """

    def __init__(self, floor: float = 0.0, *, reboot_jump: float = 1.0) -> None:
        self._offset = 0.0
        self._last_raw: float | None = None
        self._floor = floor
        self._jump = reboot_jump
        self.now = floor

    def peek(self, raw: float) -> float | None:
        """What :meth:`update` of ``raw`` would return, without updating; None where it would
        shift the offset or log (the first reading, a jump back)."""
        last = self._last_raw
        if last is None or raw < last - self._jump:
            return None
        return max(self.now, raw + self._offset)

    def update(self, raw: float) -> float:
        """Mission time of a vehicle timestamp ``raw`` (seconds)."""
        if self._last_raw is None:
            if raw < self._floor - self._jump:
                self._offset = self._floor - raw
                log.info(
                    "vehicle clock %.1f s behind the mission log; continuing from %.1f s",
                    raw,
                    self._floor,
                )
        elif raw < self._last_raw - self._jump:
            self._offset += self._last_raw - raw
            log.warning(
                "vehicle clock went back %.1f s (reboot?); mission time continues",
                self._last_raw - raw,
            )
        self._last_raw = raw
        self.now = max(self.now, raw + self._offset)
        return self.now
