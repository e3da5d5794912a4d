"""What differs between autopilots (modes, mode commands, takeoff), behind one small base class."""

from __future__ import annotations

import enum
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

from companion.autopilots.safety_params import SafetyNeeds, SafetyParam


class FlightMode(enum.Enum):
    """The modes the companion asks for; each autopilot maps them to its own custom modes."""

    GUIDED = "guided"
    """Companion in control: PX4 OFFBOARD, ArduPilot GUIDED."""
    HOLD = "hold"
    RTL = "rtl"
    LAND = "land"


@dataclass(frozen=True)
class ModeCommand:
    """Parameters 1-3 of MAV_CMD_DO_SET_MODE (176) that select a mode."""

    base_mode: float
    """MAV_MODE_FLAG_CUSTOM_MODE_ENABLED (1), ORed with SAFETY_ARMED (128) when armed."""
    custom_main: float
    """Param 2: the custom mode (ArduPilot) or PX4's main mode."""
    custom_sub: float = 0.0
    """Param 3: PX4's sub mode; 0 elsewhere."""


@dataclass(frozen=True)
class FenceParams:
    """The parameters that make an autopilot enforce an uploaded inclusion polygon."""

    enable: str | None
    """Set to 1 to enforce the fence; None: the autopilot enforces a fence as soon as it holds
    one (PX4), so the companion uploads it only once the vehicle is inside."""
    kind: str | None = None
    """Bit mask of the fence types enforced (None: no such parameter)."""
    polygon_bit: int = 0
    """The bit of ``kind`` that enforces the uploaded polygons."""
    drop_bits: int = 0
    """Bits of ``kind`` cleared: fences of their own that would cut the profile's area."""
    action: str | None = None
    """The parameter saying what a breach does (read and reported, left as the owner set it)."""


class Autopilot(ABC):
    """One autopilot family: how its modes are encoded and how it takes off."""

    name: ClassVar[str]
    """Short name used in logs and on the command line."""
    mav_autopilot: ClassVar[int]
    """MAV_AUTOPILOT value its HEARTBEAT carries."""
    takeoff_by_command: ClassVar[bool]
    """True: takeoff needs MAV_CMD_NAV_TAKEOFF (22) in the guided mode; False: setpoints climb."""
    guided_needs_stream: ClassVar[bool] = False
    """The guided mode is refused unless setpoints already flow (PX4 OFFBOARD)."""
    speed_param: ClassVar[tuple[str, float] | None] = None
    """The parameter that caps horizontal speed and its units per m/s, where there is one."""
    fence_params: ClassVar[FenceParams | None] = None
    """How the vehicle's own polygon fence is switched on, where the companion does it."""
    return_speed_params: ClassVar[tuple[tuple[str, float], ...]] = ()
    """Where the autopilot's own return (RTL) takes its horizontal speed: parameters and their
    units per m/s, the first that is set and non-zero wins (the battery reserve's way home)."""
    safety_reads: ClassVar[tuple[str, ...]] = ()
    """Parameters read before :meth:`safety_params` (the values it depends on)."""
    safety_fallbacks: ClassVar[dict[str, str]] = {}
    """An older name of one of ``safety_reads``, read only where the vehicle lacks the new."""

    def safety_params(
        self, needs: SafetyNeeds, read: Mapping[str, float | None]
    ) -> list[SafetyParam] | str:
        """The safety net's parameters (``read``: the values of ``safety_reads``, None where
        the vehicle has no such parameter), or why there can be none."""
        return f"no safety net is known for {self.name}"

    @abstractmethod
    def custom_mode(self, mode: FlightMode) -> int:
        """HEARTBEAT custom_mode the vehicle reports in ``mode``."""

    @abstractmethod
    def mode_command(self, mode: FlightMode, *, armed: bool) -> ModeCommand:
        """DO_SET_MODE parameters that select ``mode``."""

    @abstractmethod
    def mode_name(self, custom_mode: int) -> str:
        """Readable name of a reported custom mode (for logs)."""

    def is_guided(self, custom_mode: int) -> bool:
        """True when the vehicle reports the mode in which the companion may command it."""
        return custom_mode == self.custom_mode(FlightMode.GUIDED)

    def is_fallback(self, custom_mode: int) -> bool:
        """True for a mode the autopilot falls back to on its own when the companion's
        setpoints or link stop (taken back when that is why it was entered)."""
        return custom_mode == self.custom_mode(FlightMode.HOLD)

    def takeoff_params(self, altitude: float) -> tuple[float, ...]:
        """The seven parameters of MAV_CMD_NAV_TAKEOFF for a climb to ``altitude`` m above home."""
        return (0.0, 0.0, 0.0, float("nan"), float("nan"), float("nan"), altitude)
