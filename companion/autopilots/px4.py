"""PX4: custom_mode = main << 16 | sub << 24; OFFBOARD is main mode 6."""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.autopilots.base import Autopilot, FenceParams, FlightMode, ModeCommand
from companion.autopilots.safety_params import SafetyNeeds, SafetyParam

_INT32, _REAL32 = mavlink2.MAV_PARAM_TYPE_INT32, mavlink2.MAV_PARAM_TYPE_REAL32

_MAIN_SUB: dict[FlightMode, tuple[int, int]] = {
    FlightMode.GUIDED: (6, 0),
    FlightMode.HOLD: (4, 3),
    FlightMode.RTL: (4, 5),
    FlightMode.LAND: (4, 6),
}
_POSCTL = 3 << 16
_NAMES: dict[tuple[int, int], str] = {
    (1, 0): "MANUAL",
    (2, 0): "ALTCTL",
    (3, 0): "POSCTL",
    (4, 2): "TAKEOFF",
    (4, 3): "HOLD",
    (4, 4): "MISSION",
    (4, 5): "RTL",
    (4, 6): "LAND",
    (5, 0): "ACRO",
    (6, 0): "OFFBOARD",
    (7, 0): "STABILIZED",
}


class PX4(Autopilot):
    """PX4 flight stack (MAV_AUTOPILOT_PX4 = 12)."""

    name: ClassVar[str] = "px4"
    mav_autopilot: ClassVar[int] = 12
    takeoff_by_command: ClassVar[bool] = False
    guided_needs_stream: ClassVar[bool] = True
    speed_param: ClassVar[tuple[str, float] | None] = ("MPC_XY_VEL_MAX", 1.0)
    # navigator/rtl: the return flies at the mission cruise speed (stock 5 m/s)
    return_speed_params: ClassVar[tuple[tuple[str, float], ...]] = (("MPC_XY_CRUISE", 1.0),)
    # PX4's geofence (navigator/geofence.cpp) applies whatever polygon it holds, with no enable
    # parameter: GF_ACTION (stock 2, HOLD) is what a breach does, also before arming
    # ("outside geofence" refuses the arming).
    fence_params: ClassVar[FenceParams | None] = FenceParams(None, action="GF_ACTION")

    def safety_params(
        self, needs: SafetyNeeds, read: Mapping[str, float | None]
    ) -> list[SafetyParam] | str:
        # Sources: src/modules/commander/commander_params.c (COM_OBL_RC_ACT 3 = Return after
        # COM_OF_LOSS_T s without offboard setpoints; COM_LOW_BAT_ACT 3 = Return at the
        # critical level), src/modules/battery_status (BAT_CRIT_THR), navigator/geofence_params.c
        # (GF_ACTION 3 = Return, GF_MAX_VER_DIST m above home), navigator/rtl_params.c
        # (RTL_RETURN_ALT m: the return altitude, current if higher).
        top = min(needs.layer + needs.layer_band, needs.ceiling)
        return [
            SafetyParam("GF_ACTION", 3, _INT32, "fence breach: Return"),
            SafetyParam("GF_MAX_VER_DIST", needs.ceiling, _REAL32, "fence: the ceiling, m",
                        low=needs.layer + needs.layer_band, high=needs.ceiling),
            SafetyParam("COM_OBL_RC_ACT", 3, _INT32, "companion's setpoints lost: Return"),
            SafetyParam("COM_OF_LOSS_T", needs.loss_s, _REAL32, "setpoints lost after, vehicle s",
                        low=0.0, high=needs.loss_s),
            SafetyParam("COM_LOW_BAT_ACT", 3, _INT32, "battery critical: Return"),
            SafetyParam("BAT_CRIT_THR", needs.battery, _REAL32, "battery critical below",
                        low=needs.battery, high=0.5),
            SafetyParam("RTL_RETURN_ALT", needs.layer, _REAL32, "RTL altitude, m",
                        low=needs.layer - needs.layer_band, high=top),
        ]  # fmt: skip

    def custom_mode(self, mode: FlightMode) -> int:
        main, sub = _MAIN_SUB[mode]
        return main << 16 | sub << 24

    def mode_command(self, mode: FlightMode, *, armed: bool) -> ModeCommand:
        main, sub = _MAIN_SUB[mode]
        return ModeCommand(1.0 + (128.0 if armed else 0.0), float(main), float(sub))

    def is_fallback(self, custom_mode: int) -> bool:
        # Offboard loss: COM_OBL_RC_ACT 0 (stock) is POSCTL, which PX4 SITL entered when its
        # companion was killed; 5 is HOLD.
        return custom_mode in (self.custom_mode(FlightMode.HOLD), _POSCTL)

    def mode_name(self, custom_mode: int) -> str:
        key = ((custom_mode >> 16) & 0xFF, (custom_mode >> 24) & 0xFF)
        return _NAMES.get(key, f"PX4({key[0]},{key[1]})")
