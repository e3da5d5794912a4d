"""The safety net as parameters: what the autopilot itself must hold before the first arm so a
dead companion never leaves a vehicle in the air (docs/companion.md, "What the autopilot does
when the companion cannot"). Each autopilot lists its own (ardupilot.py, px4.py)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class SafetyNeeds:
    """What one vehicle's safety net must say, from its profile and its companion."""

    ceiling: float
    """The highest altitude allowed, m above the take-off point (site.max_altitude)."""
    layer: float
    """The vehicle's altitude layer, m above home: its RTL altitude."""
    layer_band: float
    """How far from the layer (m) still counts as in it (the layer watch's tolerance)."""
    companion_id: int
    """The system id of the companion's own HEARTBEAT (the GCS ArduCopter watches)."""
    battery: float
    """Fraction of the pack left at which the autopilot returns by itself."""
    loss_s: float
    """Vehicle seconds without the companion after which the autopilot returns."""
    heartbeat_s: float
    """Vehicle seconds between two of the companion's HEARTBEATs (a shorter loss time would
    fire while it runs)."""
    fence_now: bool
    """The fence may be switched on before arming: the vehicle is inside its polygon (else
    the vehicle fence switches it on once inside, companion/mission/vehicle_fence.py)."""


@dataclass(frozen=True)
class SafetyParam:
    """One parameter: the value written where it is not acceptable, and what is acceptable."""

    name: str
    wanted: float
    param_type: int
    """MAV_PARAM_TYPE of the PARAM_SET."""
    purpose: str
    """What it is for, in a few words (the console line and results.json)."""
    low: float | None = None
    high: float | None = None
    """The acceptable range; None for both: exactly ``wanted``."""
    must_bits: int = 0
    never_bits: int = 0
    """A bit mask: acceptable when these bits are set and those clear (``wanted`` ignored:
    the value written is the one read with them fixed)."""

    def accepts(self, value: float) -> bool:
        """Whether ``value`` is as the safety net needs it."""
        if self.must_bits or self.never_bits:
            v = int(value)
            return v & self.must_bits == self.must_bits and not v & self.never_bits
        if self.low is None and self.high is None:
            return abs(value - self.wanted) <= 1e-3 * max(1.0, abs(self.wanted))
        low = -float("inf") if self.low is None else self.low
        high = float("inf") if self.high is None else self.high
        return low - 1e-6 <= value <= high + 1e-6

    def to_write(self, value: float) -> float:
        """The value to write over ``value``, which :meth:`accepts` refused."""
        if self.must_bits or self.never_bits:
            return float((int(value) | self.must_bits) & ~self.never_bits)
        return self.wanted

    def needed(self) -> str:
        """The acceptable values in words, for a refusal."""
        if self.must_bits or self.never_bits:
            return f"bits {self.must_bits} set and {self.never_bits} clear"
        if self.low is None and self.high is None:
            return f"{self.wanted:g}"
        low = "" if self.low is None else f"{self.low:g}"
        high = "" if self.high is None else f"{self.high:g}"
        return f"in [{low}, {high}]"
