"""ArduPilot Copter: custom_mode is the mode number; GUIDED is 4."""

from __future__ import annotations

from typing import ClassVar

from companion.autopilots.base import Autopilot, FenceParams, FlightMode, ModeCommand

_MODES: dict[FlightMode, int] = {
    FlightMode.GUIDED: 4,
    FlightMode.HOLD: 17,  # BRAKE
    FlightMode.RTL: 6,
    FlightMode.LAND: 9,
}
_NAMES: dict[int, str] = {
    0: "STABILIZE",
    2: "ALT_HOLD",
    3: "AUTO",
    4: "GUIDED",
    5: "LOITER",
    6: "RTL",
    9: "LAND",
    16: "POSHOLD",
    17: "BRAKE",
}


class ArduCopter(Autopilot):
    """ArduPilot Copter (MAV_AUTOPILOT_ARDUPILOTMEGA = 3)."""

    name: ClassVar[str] = "ardupilot"
    mav_autopilot: ClassVar[int] = 3
    takeoff_by_command: ClassVar[bool] = True
    # GUIDED's velocity controller starts with WPNAV_SPEED as its limit (and RTL flies at it):
    # ArduCopter/mode_guided.cpp, velaccel_control_start / set_speed_xy.
    speed_param: ClassVar[tuple[str, float] | None] = ("WPNAV_SPEED", 100.0)
    # FENCE_TYPE bits (libraries/AC_Fence/AC_Fence.h): 1 max altitude, 2 circle around home
    # (FENCE_RADIUS, 300 m by default: it would cut a field area), 4 polygon, 8 min altitude.
    fence_params: ClassVar[FenceParams | None] = FenceParams(
        "FENCE_ENABLE", "FENCE_TYPE", 4, 2, "FENCE_ACTION"
    )

    def custom_mode(self, mode: FlightMode) -> int:
        return _MODES[mode]

    def mode_command(self, mode: FlightMode, *, armed: bool) -> ModeCommand:
        return ModeCommand(1.0 + (128.0 if armed else 0.0), float(_MODES[mode]))

    def mode_name(self, custom_mode: int) -> str:
        return _NAMES.get(custom_mode, f"MODE{custom_mode}")
