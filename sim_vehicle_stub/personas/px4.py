"""PX4 persona: autopilot 12, custom mode main<<16 | sub<<24, integer parameters bytewise."""

from __future__ import annotations

import math

from sim_vehicle_stub.fence_enforcement import FenceRules
from sim_vehicle_stub.params import ParamSpec, ParamTable, ParamType
from sim_vehicle_stub.personas.base import (
    LACKING_CAPABILITIES,
    Action,
    Behaviour,
    ModeSpec,
    Persona,
    ProfileFacts,
    TakeoffRequest,
    VehicleFacts,
)
from sim_vehicle_stub.personas.mission_rules import NO_ANSWER, MissionRules


def px4_mode(main: int, sub: int = 0) -> int:
    """PX4's custom_mode for a main mode and an AUTO sub mode."""
    return (main << 16) | (sub << 24)


_MAIN_AUTO = 4
_MAIN_POSCTL = 3


class Px4Persona(Persona):
    """PX4 multicopter: OFFBOARD, HOLD, RTL, LAND, TAKEOFF (and POSCTL/MANUAL for completeness)."""

    name = "px4"
    autopilot = 12
    bytewise_ints = True
    modes = (
        ModeSpec("MANUAL", px4_mode(1), Behaviour.MANUAL),
        ModeSpec("ALTCTL", px4_mode(2), Behaviour.MANUAL),
        ModeSpec("POSCTL", px4_mode(3), Behaviour.HOLD),
        ModeSpec("ORBIT", px4_mode(3, 1), Behaviour.ORBIT, armable=False),
        ModeSpec("OFFBOARD", px4_mode(6), Behaviour.EXTERNAL),
        ModeSpec("TAKEOFF", px4_mode(_MAIN_AUTO, 2), Behaviour.TAKEOFF),
        ModeSpec("HOLD", px4_mode(_MAIN_AUTO, 3), Behaviour.HOLD),
        ModeSpec("MISSION", px4_mode(_MAIN_AUTO, 4), Behaviour.MISSION),
        ModeSpec("RTL", px4_mode(_MAIN_AUTO, 5), Behaviour.RTL, armable=False),
        ModeSpec("LAND", px4_mode(_MAIN_AUTO, 6), Behaviour.LAND, armable=False),
    )
    default_mode = "HOLD"
    external_mode = "OFFBOARD"
    hold_mode = "HOLD"
    rtl_mode = "RTL"
    land_mode = "LAND"
    position_mode = "POSCTL"
    offboard_needs_setpoints = True
    position_targets_time_out = True
    takeoff_while_disarmed = True
    takeoff_refusal = 2  # MAV_RESULT_DENIED
    reposition_mode = "HOLD"
    mode_after_landing = "HOLD"
    reposition_elsewhere = 0  # ACCEPTED: commander switches nothing without the flag
    mission_mode = "MISSION"
    mission = MissionRules(
        home_is_item0=False,
        legacy_requests_only=False,
        partial_lists=False,
        max_items=65535,
        fence_takes_any_command=True,
        global_frame_nav_only=True,
        past_end_answer=NO_ANSWER,
        reports_mission_state=False,
        current_unasked=True,
        acceptance_param="NAV_ACC_RAD",
        acceptance_scale=1.0,
        start_needs_armed=True,
        set_current_without_mission=3,
        takeoff_when_landed=True,
        rtl_item_switches_mode=True,
        clears_all_types=True,
        checks_item_numbers=False,
        auto_armable=True,
    )
    # PX4 SITL 1.16-dev: capabilities 0xe8ff, flight_sw_version 0x01100000 (1.16.0 dev).
    capabilities = 0xE8FF & ~LACKING_CAPABILITIES
    firmware_version = 0x01100000
    unknown_mode_result = 2  # DENIED
    manual_modes = frozenset(("MANUAL", "ALTCTL", "POSCTL"))
    data_streams = False
    flight_commands = frozenset((300, 179, 34))
    """MISSION_START, DO_SET_HOME, DO_ORBIT (PX4 SITL answers DO_SET_MISSION_CURRENT,
    DO_FENCE_ENABLE, CONDITION_YAW and NAV_LOITER_UNLIM with UNSUPPORTED, a mission loaded or
    not)."""
    fixed_intervals = frozenset((42,))
    """MISSION_CURRENT: SET_MESSAGE_INTERVAL answered FAILED on PX4 SITL."""
    unrequestable = frozenset((42, 65, 74))
    """MISSION_CURRENT, RC_CHANNELS, VFR_HUD: REQUEST_MESSAGE DENIED on PX4 SITL."""

    def param_specs(self, facts: ProfileFacts) -> list[ParamSpec]:
        s = facts.timeout_scale
        i32 = ParamType.INT32
        return [
            ParamSpec("MAV_SYS_ID", facts.system_id, i32, 1, 255),
            ParamSpec("COM_OF_LOSS_T", 1.0 * s, low=0.0, doc="offboard setpoint loss, s"),
            # Stock values read from PX4 SITL (SIH, February 2025) where they matter here.
            ParamSpec("COM_OBL_RC_ACT", 0, i32, 0, 7, "offboard loss: 0 position, 3 RTL, 4 land"),
            ParamSpec("COM_DL_LOSS_T", round(10 * s), i32, 5, 1e6, "data link loss, s"),
            ParamSpec("NAV_DLL_ACT", 0, i32, 0, 6, "link loss: 0 off, 1 hold, 2 RTL, 3 land"),
            ParamSpec("GF_ACTION", 2, i32, 0, 5, "fence: 0/1 none, 2 hold, 3 RTL, 5 land"),
            ParamSpec("GF_MAX_HOR_DIST", 0.0, low=0.0, high=1e4, doc="m from home, 0 off"),
            ParamSpec("GF_MAX_VER_DIST", 0.0, low=0.0, high=1e4, doc="m above home, 0 off"),
            ParamSpec("NAV_ACC_RAD", 2.0, low=0.05, high=200.0, doc="waypoint radius, m"),
            # Listed only (stock values read from PX4 SITL), so a preflight can set them.
            ParamSpec("GF_SOURCE", 0, i32, 0, 1, "listed only"),
            ParamSpec("GF_PREDICT", 0, i32, 0, 1, "listed only"),
            ParamSpec("NAV_RCL_ACT", 2, i32, 0, 6, "listed only: no RC link is emulated"),
            ParamSpec("COM_RCL_EXCEPT", 0, i32, 0, 7, "listed only"),
            ParamSpec("BAT_CRIT_THR", 0.07, low=0.0, high=1.0),
            ParamSpec("COM_LOW_BAT_ACT", 3, i32, 0, 3, "0 warn, 2 land, 3 RTL at critical"),
            ParamSpec("MIS_TAKEOFF_ALT", 2.5, low=0.0, high=1e4),
            # PX4's range is 0-20 m/s (mc_pos_control params), widened for a faster profile;
            # the profile's speed is the companion's to set (DO_CHANGE_SPEED, this parameter).
            ParamSpec("MPC_XY_VEL_MAX", 12.0, low=0.1, high=max(20.0, facts.speed)),
            ParamSpec("MPC_XY_CRUISE", 5.0, low=1.0, high=max(20.0, facts.speed), doc="AUTO m/s"),
            ParamSpec("MPC_Z_VEL_MAX_UP", 3.0, low=0.1, high=100.0),
            ParamSpec("MPC_Z_VEL_MAX_DN", 1.5, low=0.1, high=100.0),
            ParamSpec("MPC_LAND_SPEED", 0.7, low=0.1, high=100.0),
            ParamSpec("MPC_TKO_SPEED", 1.5, low=1.0, high=5.0, doc="takeoff climb rate, m/s"),
            ParamSpec("RTL_RETURN_ALT", 30.0, low=0.0, high=1e4),
            ParamSpec("COM_RC_LOSS_T", 0.5 * s, low=0.0, high=1e6, doc="manual control loss, s"),
        ]

    def mode_from_command(self, p1: float, p2: float, p3: float) -> ModeSpec | None:
        if not (math.isfinite(p2) and math.isfinite(p3)):
            return None
        main, sub = int(p2), int(p3)
        if main not in (_MAIN_AUTO, _MAIN_POSCTL):
            sub = 0
        return self.mode_by_custom(px4_mode(main, sub)) or self.mode_by_custom(px4_mode(main))

    def takeoff(self, p7: float, params: ParamTable, vehicle: VehicleFacts) -> TakeoffRequest | str:
        # PX4 reads param7 as AMSL; below home + MIS_TAKEOFF_ALT (or NaN) it climbs to
        # MIS_TAKEOFF_ALT (navigator/takeoff.cpp, set_takeoff_position: "Using minimum takeoff
        # altitude"). Commander accepts the command disarmed too: it only selects TAKEOFF.
        minimum = params.get("MIS_TAKEOFF_ALT")
        altitude = p7 - vehicle.home_alt_amsl if math.isfinite(p7) else -math.inf
        if not math.isfinite(altitude):
            altitude = minimum  # an AMSL request so large it overflows is no altitude either
        if altitude < minimum:
            return TakeoffRequest(
                minimum, self.mode("TAKEOFF"), f"Using minimum takeoff altitude: {minimum:.2f} m"
            )
        return TakeoffRequest(altitude, self.mode("TAKEOFF"))

    def after_takeoff(self) -> ModeSpec | None:
        return self.mode("HOLD")

    def setpoint_loss(self, params: ParamTable) -> tuple[float, Action]:
        act = int(params.get("COM_OBL_RC_ACT"))
        # PX4 SITL without RC, stock 0: POSCTL (measured after a companion was killed).
        action = {0: Action.POSITION, 3: Action.RTL, 4: Action.LAND}.get(act, Action.HOLD)
        return params.get("COM_OF_LOSS_T"), action

    def link_loss(self, params: ParamTable) -> tuple[float, Action]:
        act = int(params.get("NAV_DLL_ACT"))
        action = {1: Action.HOLD, 2: Action.RTL, 3: Action.LAND}.get(act, Action.NONE)
        return params.get("COM_DL_LOSS_T"), action

    def fence_action(self, params: ParamTable) -> Action:
        act = int(params.get("GF_ACTION"))
        return {2: Action.HOLD, 3: Action.RTL, 5: Action.LAND}.get(act, Action.NONE)

    def fence_rules(self, params: ParamTable) -> FenceRules | None:
        return FenceRules(
            alt_max=params.get("GF_MAX_VER_DIST"),
            radius=params.get("GF_MAX_HOR_DIST"),
            polygons=True,
            union=True,
        )

    def low_battery(self, params: ParamTable) -> tuple[float, Action]:
        act = int(params.get("COM_LOW_BAT_ACT"))
        action = {2: Action.LAND, 3: Action.RTL}.get(act, Action.NONE)
        return params.get("BAT_CRIT_THR"), action

    def speeds(self, params: ParamTable) -> tuple[float, float, float, float]:
        return (
            params.get("MPC_XY_VEL_MAX"),
            params.get("MPC_Z_VEL_MAX_UP"),
            params.get("MPC_Z_VEL_MAX_DN"),
            params.get("MPC_LAND_SPEED"),
        )

    def mission_speed(self, params: ParamTable) -> float:
        # FlightTaskAuto: waypoints at MPC_XY_CRUISE, capped at MPC_XY_VEL_MAX.
        return min(params.get("MPC_XY_CRUISE"), params.get("MPC_XY_VEL_MAX"))

    def speed_limits(self, params: ParamTable) -> tuple[float, float, float, float]:
        # FlightTaskAuto caps the cruise speed at MPC_XY_VEL_MAX, and the position controller
        # every velocity (mc_pos_control/PositionControl): a change of speed cannot exceed them.
        return self.speeds(params)

    def takeoff_climb(self, params: ParamTable) -> float | None:
        # FlightTaskAuto's takeoff climbs at MPC_TKO_SPEED (PX4 SITL: 1.9 m/s measured between
        # 5 and 15 m on a 20 m takeoff, the ramp towards MPC_Z_V_AUTO_UP not modelled).
        return float(params.get("MPC_TKO_SPEED"))

    def rtl_altitude(self, params: ParamTable) -> float:
        return params.get("RTL_RETURN_ALT")

    def stick_timeout(self, params: ParamTable) -> float:
        return params.get("COM_RC_LOSS_T")
