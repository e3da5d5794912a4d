"""ArduPilot Copter: custom_mode is the mode number; GUIDED is 4."""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.autopilots.base import Autopilot, FenceParams, FlightMode, ModeCommand
from companion.autopilots.safety_params import SafetyNeeds, SafetyParam

_INT8, _INT16, _INT32 = (
    mavlink2.MAV_PARAM_TYPE_INT8,
    mavlink2.MAV_PARAM_TYPE_INT16,
    mavlink2.MAV_PARAM_TYPE_INT32,
)
_REAL32 = mavlink2.MAV_PARAM_TYPE_REAL32

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
    # The GCS it watches: MAV_GCS_SYSID in 4.7 (the SITL of ../shared/sitl), SYSID_MYGCS before.
    # mode_rtl.cpp: RTL_SPEED cm/s, 0: WPNAV_SPEED
    return_speed_params: ClassVar[tuple[tuple[str, float], ...]] = (
        ("RTL_SPEED", 100.0),
        ("WPNAV_SPEED", 100.0),
    )
    safety_reads: ClassVar[tuple[str, ...]] = ("BATT_CAPACITY", "MAV_GCS_SYSID")
    safety_fallbacks: ClassVar[dict[str, str]] = {"MAV_GCS_SYSID": "SYSID_MYGCS"}

    def safety_params(
        self, needs: SafetyNeeds, read: Mapping[str, float | None]
    ) -> list[SafetyParam] | str:
        # Sources: ArduCopter/Parameters.cpp (FS_GCS_ENABLE 1 = RTL, FS_GCS_TIMEOUT s),
        # libraries/GCS_MAVLink (MAV_GCS_SYSID: only that system's HEARTBEAT counts),
        # libraries/AC_Fence/AC_Fence.cpp (FENCE_ACTION 1 = RTL, FENCE_ALT_MAX m),
        # libraries/AP_BattMonitor (BATT_FS_LOW_ACT 2 = RTL at BATT_LOW_MAH left),
        # ArduCopter/mode_rtl.cpp (RTL_ALT cm: the return altitude, current if higher).
        capacity = read.get("BATT_CAPACITY")
        if capacity is None or capacity <= 0:
            return f"BATT_CAPACITY is {capacity}: no battery failsafe by the mAh left"
        gcs = next((n for n in ("MAV_GCS_SYSID", "SYSID_MYGCS") if read.get(n) is not None), None)
        if gcs is None:
            return "neither MAV_GCS_SYSID nor SYSID_MYGCS: no GCS failsafe on the companion"
        top = min(needs.layer + needs.layer_band, needs.ceiling)
        short = max(2.0, 2.0 * needs.heartbeat_s)  # ArduCopter's FS_GCS_TIMEOUT minimum is 2
        low_mah = round(capacity * needs.battery)
        params = [
            SafetyParam("FENCE_TYPE", 0, _INT8, "fence: max altitude on, circle off",
                        must_bits=1, never_bits=2),
            SafetyParam("FENCE_ACTION", 1, _INT8, "fence breach: RTL"),
            SafetyParam("FENCE_ALT_MAX", needs.ceiling, _REAL32, "fence: the ceiling, m",
                        low=needs.layer + needs.layer_band, high=needs.ceiling),
            SafetyParam("FS_GCS_ENABLE", 1, _INT8, "companion lost: RTL"),
            SafetyParam(gcs, needs.companion_id, _INT16, "the GCS watched: the companion"),
            SafetyParam("FS_GCS_TIMEOUT", max(needs.loss_s, short), _REAL32,
                        "companion lost after, vehicle s", low=short,
                        high=max(needs.loss_s, short)),
            SafetyParam("BATT_FS_LOW_ACT", 2, _INT8, "battery low: RTL"),
            SafetyParam("BATT_LOW_MAH", low_mah, _INT32, "battery low below, mAh",
                        low=low_mah, high=capacity / 2),
            SafetyParam("RTL_ALT", round(needs.layer * 100), _INT32, "RTL altitude, cm",
                        low=(needs.layer - needs.layer_band) * 100, high=top * 100),
        ]  # fmt: skip
        if needs.fence_now:
            params.insert(0, SafetyParam("FENCE_ENABLE", 1, _INT8, "fence on"))
        return params

    def custom_mode(self, mode: FlightMode) -> int:
        return _MODES[mode]

    def mode_command(self, mode: FlightMode, *, armed: bool) -> ModeCommand:
        return ModeCommand(1.0 + (128.0 if armed else 0.0), float(_MODES[mode]))

    def mode_name(self, custom_mode: int) -> str:
        return _NAMES.get(custom_mode, f"MODE{custom_mode}")
