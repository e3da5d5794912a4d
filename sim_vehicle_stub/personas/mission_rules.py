"""What differs between autopilots in the mission protocol and in AUTO: persona data.

Every value was measured on ArduCopter SITL (4.7-dev, July 2025) and PX4 SITL (1.16-dev SIH,
February 2025) by uploading, downloading and flying plans with pymavlink; see
docs/protocol.md, *Missions*.
"""

from __future__ import annotations

from dataclasses import dataclass

from sim_vehicle_stub.mavlink import dialect as d

NAV_COMMANDS = frozenset(
    (
        d.MAV_CMD_NAV_WAYPOINT,
        d.MAV_CMD_NAV_LOITER_UNLIM,
        d.MAV_CMD_NAV_LOITER_TURNS,
        d.MAV_CMD_NAV_LOITER_TIME,
        d.MAV_CMD_NAV_RETURN_TO_LAUNCH,
        d.MAV_CMD_NAV_LAND,
        d.MAV_CMD_NAV_TAKEOFF,
        d.MAV_CMD_NAV_LOITER_TO_ALT,
        d.MAV_CMD_NAV_DELAY,
        d.MAV_CMD_NAV_SPLINE_WAYPOINT,
    )
)
POSITION_COMMANDS = NAV_COMMANDS - {
    d.MAV_CMD_NAV_RETURN_TO_LAUNCH,
    d.MAV_CMD_NAV_DELAY,
    d.MAV_CMD_NAV_SPLINE_WAYPOINT,
}
"""The items PX4 takes in a global frame (its parse of a global-frame item knows no others)."""
DO_COMMANDS = frozenset(
    (
        d.MAV_CMD_DO_JUMP,
        d.MAV_CMD_DO_CHANGE_SPEED,
        d.MAV_CMD_DO_SET_HOME,
        d.MAV_CMD_DO_SET_SERVO,
        d.MAV_CMD_DO_SET_RELAY,
        d.MAV_CMD_DO_SET_ROI,
        d.MAV_CMD_DO_SET_ROI_LOCATION,
        d.MAV_CMD_DO_SET_ROI_NONE,
        d.MAV_CMD_DO_DIGICAM_CONTROL,
        d.MAV_CMD_DO_MOUNT_CONTROL,
        d.MAV_CMD_DO_SET_CAM_TRIGG_DIST,
        d.MAV_CMD_DO_FENCE_ENABLE,
        d.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW,
        d.MAV_CMD_CONDITION_DELAY,
        d.MAV_CMD_CONDITION_DISTANCE,
        d.MAV_CMD_CONDITION_YAW,
        d.MAV_CMD_IMAGE_START_CAPTURE,
        d.MAV_CMD_IMAGE_STOP_CAPTURE,
        d.MAV_CMD_VIDEO_START_CAPTURE,
        d.MAV_CMD_VIDEO_STOP_CAPTURE,
        d.MAV_CMD_DO_CHANGE_ALTITUDE,
    )
)
"""Commands a mission may carry that the emulator stores (and executes where it can: the camera,
servo and gimbal items are stored and skipped, as a vehicle without that hardware does)."""
FENCE_COMMANDS = frozenset(
    range(d.MAV_CMD_NAV_FENCE_RETURN_POINT, d.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION + 1)
)
"""5000 return point, 5001/5002 polygon vertex inclusion/exclusion, 5003/5004 circles."""
RALLY_COMMANDS = frozenset((d.MAV_CMD_NAV_RALLY_POINT,))
YAW_MAY_BE_NAN = frozenset((d.MAV_CMD_NAV_WAYPOINT, d.MAV_CMD_NAV_TAKEOFF, d.MAV_CMD_NAV_LAND))
"""The items whose param4 (yaw) ArduPilot takes as NaN (AP_Mission::sanity_check_params)."""
LOCATION_COMMANDS = frozenset(
    (
        d.MAV_CMD_NAV_WAYPOINT,
        d.MAV_CMD_NAV_LOITER_UNLIM,
        d.MAV_CMD_NAV_LOITER_TURNS,
        d.MAV_CMD_NAV_LOITER_TIME,
        d.MAV_CMD_NAV_LAND,
        d.MAV_CMD_NAV_TAKEOFF,
        d.MAV_CMD_NAV_LOITER_TO_ALT,
        d.MAV_CMD_NAV_SPLINE_WAYPOINT,
        d.MAV_CMD_DO_SET_HOME,
        d.MAV_CMD_DO_SET_ROI,
    )
)
"""The stored items ArduPilot keeps a location in (AP_Mission::stored_in_location): their
altitude (z) must be a number below 83 km."""
GLOBAL_FRAMES = frozenset((0, 3, 5, 6, 10, 11))
"""GLOBAL, GLOBAL_RELATIVE_ALT, GLOBAL_INT, GLOBAL_RELATIVE_ALT_INT, GLOBAL_TERRAIN_ALT(_INT)."""
MISSION_FRAME = d.MAV_FRAME_MISSION
NO_ANSWER = -1
"""An answer slot meaning: the autopilot sends nothing."""


@dataclass(frozen=True)
class MissionRules:
    """One autopilot's mission protocol and AUTO behaviour."""

    home_is_item0: bool
    """ArduPilot stores home as mission item 0 (a download gives home there; MISSION_CURRENT
    counts the items after it)."""
    legacy_requests_only: bool
    """ArduPilot asks for every item with MISSION_REQUEST (and takes either item message);
    PX4 asks the way the client's last item came."""
    partial_lists: bool
    """MISSION_WRITE_PARTIAL_LIST is taken (ArduPilot) or ignored (PX4)."""
    max_items: int
    """A longer MISSION_COUNT is refused at once with NO_SPACE."""
    fence_takes_any_command: bool
    """PX4 stores a non-fence command in a fence upload; ArduPilot answers UNSUPPORTED."""
    global_frame_nav_only: bool
    """PX4 takes only position items (NAV_*, fence, rally) in a global frame; a DO_ command or
    RETURN_TO_LAUNCH there is UNSUPPORTED (QGroundControl sends them in MAV_FRAME_MISSION)."""
    past_end_answer: int
    """Answer to MISSION_REQUEST(_INT) past the last item: INVALID_SEQUENCE (ArduPilot), or
    NO_ANSWER (PX4)."""
    reports_mission_state: bool
    """MISSION_CURRENT carries mission_state and mission_mode (ArduPilot) or 0 (PX4)."""
    current_unasked: bool
    """MISSION_CURRENT goes out on a link that did not ask for it: PX4 streams it by default; a
    stock ArduCopter sends none there, neither streamed nor at an item change, until a client
    asks (SET_MESSAGE_INTERVAL, REQUEST_DATA_STREAM EXTENDED_STATUS). Measured on ArduCopter
    SITL: MAVSDK flying a plan on SERIAL0 got only MISSION_ITEM_REACHED, so its mission
    progress starts at 2 (after the take-off item is reached); SERIAL1, asking 10 Hz, got
    MISSION_CURRENT 1 for the take-off."""
    acceptance_param: str
    """The waypoint acceptance radius used when an item's param2 is 0."""
    acceptance_scale: float
    """Parameter units per metre (WPNAV_RADIUS is cm)."""
    start_needs_armed: bool
    """MISSION_START while disarmed: PX4 DENIED, ArduPilot switches to AUTO (ACCEPTED)."""
    set_current_without_mission: int
    """DO_SET_MISSION_CURRENT with no mission (ArduPilot: DENIED)."""
    takeoff_when_landed: bool
    """PX4 climbs to the first waypoint's altitude (a takeoff of its own) when a mission
    without a NAV_TAKEOFF starts on the ground; ArduCopter refuses AUTO armed on the ground
    without a takeoff item ("Auto: Missing Takeoff Cmd")."""
    rtl_item_switches_mode: bool
    """A NAV_RETURN_TO_LAUNCH item: PX4's navigator hands over to its RTL mode; ArduCopter
    flies the return inside AUTO."""
    auto_armable: bool
    """PX4 arms in AUTO.MISSION; ArduCopter does not (AUTO_OPTIONS 0)."""
    clears_all_types: bool
    """MISSION_CLEAR_ALL of MAV_MISSION_TYPE_ALL clears every plan (PX4) or is UNSUPPORTED
    (ArduCopter, which clears nothing then)."""
    checks_item_numbers: bool
    """ArduPilot refuses a mission item (before looking at its command or frame) whose param1-4
    is infinite, or NaN other than the yaw (param4) of YAW_MAY_BE_NAN: INVALID_PARAM1..4; and
    one of LOCATION_COMMANDS whose altitude is NaN or 83 km or more: INVALID_PARAM7. MAVSDK's
    mission plugin sends its return-to-launch item with four NaN params, so ArduCopter refuses
    that upload (MAVSDK: INVALID_ARGUMENT). PX4 stores such items."""
