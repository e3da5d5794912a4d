"""ArduPilot Copter persona: autopilot 3, custom mode = mode number, parameters float-cast."""

from __future__ import annotations

import math

from sim_vehicle_stub.fence_enforcement import FenceRules
from sim_vehicle_stub.mavlink import dialect as d
from sim_vehicle_stub.orbit import Orbit, circle_ahead
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
from sim_vehicle_stub.personas.mission_rules import MissionRules

LOCATION_ALT_MAX_M = 83000.0
"""The highest altitude ArduPilot's Location can hold (libraries/AP_Common/Location.h)."""


class ArduCopterPersona(Persona):
    """ArduCopter: GUIDED, AUTO, LOITER, POSHOLD, CIRCLE, RTL, SMART_RTL, LAND, BRAKE (STABILIZE
    on the ground at boot, ALT_HOLD)."""

    name = "ardupilot"
    autopilot = 3
    bytewise_ints = False
    modes = (
        ModeSpec("STABILIZE", 0, Behaviour.MANUAL),
        ModeSpec("ALT_HOLD", 2, Behaviour.MANUAL),
        ModeSpec("AUTO", 3, Behaviour.MISSION, armable=False),
        ModeSpec("GUIDED", 4, Behaviour.EXTERNAL),
        ModeSpec("LOITER", 5, Behaviour.HOLD),
        ModeSpec("RTL", 6, Behaviour.RTL, armable=False),
        ModeSpec("CIRCLE", 7, Behaviour.ORBIT, armable=False),
        ModeSpec("LAND", 9, Behaviour.LAND, armable=False),
        ModeSpec("POSHOLD", 16, Behaviour.HOLD),
        ModeSpec("BRAKE", 17, Behaviour.HOLD, armable=False),
        ModeSpec("SMART_RTL", 21, Behaviour.RTL, armable=False),
    )
    default_mode = "STABILIZE"
    external_mode = "GUIDED"
    hold_mode = "BRAKE"
    rtl_mode = "RTL"
    land_mode = "LAND"
    offboard_needs_setpoints = False
    position_targets_time_out = False
    takeoff_while_disarmed = False
    takeoff_refusal = 4  # MAV_RESULT_FAILED: handle_MAV_CMD_NAV_TAKEOFF when do_user_takeoff fails
    reposition_mode = "GUIDED"
    reposition_elsewhere = 2  # DENIED: handle_command_int_do_reposition outside GUIDED
    mission_mode = "AUTO"
    mission = MissionRules(
        home_is_item0=True,
        legacy_requests_only=True,
        partial_lists=True,
        max_items=724,
        fence_takes_any_command=False,
        global_frame_nav_only=False,
        past_end_answer=d.MAV_MISSION_INVALID_SEQUENCE,
        reports_mission_state=True,
        current_unasked=False,
        acceptance_param="WPNAV_RADIUS",
        acceptance_scale=100.0,
        start_needs_armed=False,
        set_current_without_mission=2,
        takeoff_when_landed=False,
        rtl_item_switches_mode=False,
        clears_all_types=False,
        checks_item_numbers=True,
        auto_armable=False,
    )
    # ArduCopter SITL 4.7-dev: capabilities 0xfbef, flight_sw_version 0x04070000 (4.7.0 dev).
    capabilities = 0xFBEF & ~LACKING_CAPABILITIES
    firmware_version = 0x04070000
    unknown_mode_result = 4  # FAILED: DO_SET_MODE FLIP/SPORT/FOLLOW on the SITL build
    manual_modes = frozenset(("STABILIZE", "ALT_HOLD", "LOITER", "POSHOLD"))
    data_streams = True
    reports_geofence = True
    flight_commands = frozenset((300, 224, 207, 179, 115, 17))
    """MISSION_START, DO_SET_MISSION_CURRENT, DO_FENCE_ENABLE, DO_SET_HOME, CONDITION_YAW,
    NAV_LOITER_UNLIM: all ACCEPTED by ArduCopter SITL (DO_ORBIT is UNSUPPORTED there)."""
    fence_enable_param = "FENCE_ENABLE"
    loiter_mode = "LOITER"

    def param_specs(self, facts: ProfileFacts) -> list[ParamSpec]:
        s = facts.timeout_scale
        i8, i32 = ParamType.INT8, ParamType.INT32
        return [
            ParamSpec("SYSID_THISMAV", facts.system_id, i8, 1, 255),
            # ArduCopter 4.7's name (SYSID_MYGCS before): only this system's HEARTBEAT counts.
            ParamSpec("MAV_GCS_SYSID", 255, i32, 1, 255, "the GCS the GCS failsafe watches"),
            ParamSpec("GUID_TIMEOUT", 3.0 * s, low=0.1, doc="guided velocity target time-out, s"),
            ParamSpec("FS_GCS_ENABLE", 0, i8, 0, 7, "GCS loss: 0 off, 1/2/3/6 RTL, 4/5 land"),
            ParamSpec("FS_GCS_TIMEOUT", 5.0 * s, low=2.0, high=1e6),
            ParamSpec("FENCE_ENABLE", 1, i8, 0, 1, "search-area fence on"),
            ParamSpec("FENCE_TYPE", 4, i8, 0, 15, "1 alt max, 2 circle, 4 polygons and the area"),
            ParamSpec("FENCE_ACTION", 1, i8, 0, 5, "0 report, 1/3/5 RTL, 2 land, 4 brake"),
            ParamSpec("FENCE_ALT_MAX", 100.0, low=10.0, high=1000.0, doc="m, FENCE_TYPE bit 0"),
            ParamSpec("FENCE_ALT_MIN", -10.0, low=-100.0, high=100.0, doc="m, FENCE_TYPE bit 3"),
            ParamSpec("FENCE_RADIUS", 150.0, low=30.0, high=10000.0, doc="m, FENCE_TYPE bit 1"),
            ParamSpec("FENCE_MARGIN", 2.0, low=1.0, high=10.0, doc="m inside a fence"),
            ParamSpec("WPNAV_RADIUS", 200.0, low=5.0, high=1000.0, doc="waypoint radius, cm"),
            # Listed only (stock values read from ArduCopter SITL), so a preflight can set them.
            ParamSpec("FS_OPTIONS", 16, i32, 0, 1023, "listed only"),
            ParamSpec("WP_YAW_BEHAVIOR", 2, i8, 0, 3, "listed only"),
            ParamSpec("RTL_ALT_FINAL", 0, i32, 0, 1000, "listed only, cm"),
            # mode_rtl.cpp's return speed (0: WPNAV_SPEED), read by the companion's battery
            # reserve; the persona's RTL flies at its speed limit whatever it holds.
            ParamSpec("RTL_SPEED", 0, ParamType.INT16, 0, 2000, "listed only, cm/s"),
            ParamSpec("BATT_CAPACITY", 5200, i32, 0, 1e6, "mAh"),
            ParamSpec("BATT_LOW_MAH", 800, i32, 0, 1e6, "mAh left that trigger the failsafe"),
            ParamSpec("BATT_FS_LOW_ACT", 2, i8, 0, 5, "0 none, 1 land, 2 RTL"),
            # Range 20-2000 cm/s as ArduCopter's (AC_WPNav.cpp), widened for a faster profile.
            ParamSpec(
                "WPNAV_SPEED",
                facts.speed * 100.0,
                low=20.0,
                high=max(2000.0, facts.speed * 100.0),
                doc="cm/s",
            ),
            ParamSpec("WPNAV_SPEED_UP", 250.0, low=10.0, high=1e4, doc="cm/s"),
            ParamSpec("WPNAV_SPEED_DN", 150.0, low=10.0, high=1e4, doc="cm/s"),
            ParamSpec("LAND_SPEED", 50.0, low=10.0, high=1e4, doc="cm/s"),
            ParamSpec("RTL_ALT", 1500.0, low=0.0, high=1e6, doc="cm"),
            ParamSpec("CIRCLE_RADIUS", 1000.0, low=0.0, high=2e5, doc="cm"),
            ParamSpec("CIRCLE_RATE", 20.0, low=-90.0, high=90.0, doc="deg/s, + clockwise"),
            ParamSpec("RC_OVERRIDE_TIME", 3.0 * s, low=-1.0, high=1e6, doc="RC override, s"),
        ]

    def mode_from_command(self, p1: float, p2: float, p3: float) -> ModeSpec | None:
        if not math.isfinite(p2):
            return None
        return self.mode_by_custom(int(p2))

    def takeoff(self, p7: float, params: ParamTable, vehicle: VehicleFacts) -> TakeoffRequest | str:
        if vehicle.mode.behaviour is not Behaviour.EXTERNAL:
            return "takeoff needs GUIDED"
        if not vehicle.armed:
            return "not armed"
        if not vehicle.landed:
            return "already flying"
        if not (math.isfinite(p7) and p7 > 0):
            return f"takeoff altitude {p7} m is not above home"
        if p7 >= LOCATION_ALT_MAX_M:
            return f"takeoff altitude {p7:.0f} m beyond {LOCATION_ALT_MAX_M} m"
        return TakeoffRequest(p7, None)

    def after_takeoff(self) -> ModeSpec | None:
        return None

    def setpoint_loss(self, params: ParamTable) -> tuple[float, Action]:
        return params.get("GUID_TIMEOUT"), Action.HOLD

    def link_loss(self, params: ParamTable) -> tuple[float, Action]:
        act = int(params.get("FS_GCS_ENABLE"))
        action = Action.NONE
        if act in (1, 2, 3, 6):
            action = Action.RTL
        elif act in (4, 5):
            action = Action.LAND
        return params.get("FS_GCS_TIMEOUT"), action

    def watches_heartbeat(self, params: ParamTable, sysid: int) -> bool:
        # GCS_MAVLINK::handle_heartbeat: only MAV_GCS_SYSID's heartbeat resets the failsafe.
        return sysid == int(params.get("MAV_GCS_SYSID"))

    def fence_action(self, params: ParamTable) -> Action:
        if int(params.get("FENCE_ENABLE")) == 0:
            return Action.NONE
        act = int(params.get("FENCE_ACTION"))
        return {1: Action.RTL, 3: Action.RTL, 5: Action.RTL, 2: Action.LAND, 4: Action.HOLD}.get(
            act, Action.NONE
        )

    def fence_rules(self, params: ParamTable) -> FenceRules | None:
        if int(params.get("FENCE_ENABLE")) == 0:
            return None
        kind = int(params.get("FENCE_TYPE"))
        return FenceRules(
            alt_max=params.get("FENCE_ALT_MAX") if kind & 1 else 0.0,
            radius=params.get("FENCE_RADIUS") if kind & 2 else 0.0,
            polygons=bool(kind & 4),
            union=False,
        )

    def low_battery(self, params: ParamTable) -> tuple[float, Action]:
        capacity = params.get("BATT_CAPACITY")
        threshold = params.get("BATT_LOW_MAH") / capacity if capacity > 0 else 0.0
        act = int(params.get("BATT_FS_LOW_ACT"))
        return threshold, {1: Action.LAND, 2: Action.RTL}.get(act, Action.NONE)

    def speeds(self, params: ParamTable) -> tuple[float, float, float, float]:
        return (
            params.get("WPNAV_SPEED") / 100.0,
            params.get("WPNAV_SPEED_UP") / 100.0,
            params.get("WPNAV_SPEED_DN") / 100.0,
            params.get("LAND_SPEED") / 100.0,
        )

    def mission_speed(self, params: ParamTable) -> float:
        return params.get("WPNAV_SPEED") / 100.0

    def speed_limits(self, params: ParamTable) -> tuple[float, float, float, float]:
        # The upper ends of the WPNAV_SPEED / _UP / _DN and LAND_SPEED ranges (ArduCopter
        # AC_WPNav/AC_WPNav.cpp parameter docs): what the stock airframe is tuned to fly.
        return params.spec("WPNAV_SPEED").high / 100.0, 10.0, 5.0, 2.0

    def rtl_altitude(self, params: ParamTable) -> float:
        return params.get("RTL_ALT") / 100.0

    def orbit_entered(self, params: ParamTable, north: float, east: float, yaw: float) -> Orbit:
        # ModeCircle: the centre CIRCLE_RADIUS ahead, turning at CIRCLE_RATE.
        radius = params.get("CIRCLE_RADIUS") / 100.0
        return circle_ahead(north, east, yaw, radius, params.get("CIRCLE_RATE"))

    def stick_timeout(self, params: ParamTable) -> float:
        t = params.get("RC_OVERRIDE_TIME")
        return math.inf if t < 0 else t
