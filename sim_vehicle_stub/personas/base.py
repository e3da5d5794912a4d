"""What every autopilot persona provides: modes, their encoding, parameters and failsafe choices."""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from enum import Enum
from typing import ClassVar

from sim_vehicle_stub.fence_enforcement import FenceRules
from sim_vehicle_stub.mavlink import dialect as d
from sim_vehicle_stub.orbit import Orbit, orbit_about
from sim_vehicle_stub.params import ParamSpec, ParamTable, ParamType
from sim_vehicle_stub.personas.mission_rules import MissionRules

LACKING_CAPABILITIES = (
    d.MAV_PROTOCOL_CAPABILITY_FTP
    | d.MAV_PROTOCOL_CAPABILITY_TERRAIN
    | d.MAV_PROTOCOL_CAPABILITY_FLIGHT_TERMINATION
    | d.MAV_PROTOCOL_CAPABILITY_COMPASS_CALIBRATION
)
"""Capabilities the real autopilots report that the emulator does not have."""


class Behaviour(Enum):
    """What the vehicle does in a mode, independent of the autopilot's name for it."""

    MANUAL = "manual"
    """No pilot here: holds position when airborne, idles on the ground."""
    EXTERNAL = "external"
    """Follows SET_POSITION_TARGET_* (PX4 OFFBOARD, ArduPilot GUIDED)."""
    HOLD = "hold"
    """Stops and holds position and altitude."""
    TAKEOFF = "takeoff"
    LAND = "land"
    RTL = "rtl"
    MISSION = "mission"
    """Flies the stored mission (ArduCopter AUTO, PX4 AUTO.MISSION): mission_flight.py."""
    ORBIT = "orbit"
    """Circles a point (ArduCopter CIRCLE, PX4 ORBIT): orbit.py."""


class Action(Enum):
    """A failsafe's reaction, mapped to a mode by the persona."""

    NONE = "none"
    HOLD = "hold"
    POSITION = "position"
    """Position mode: holds without sticks (PX4's offboard-loss default, COM_OBL_RC_ACT 0)."""
    RTL = "rtl"
    LAND = "land"


@dataclass(frozen=True)
class ModeSpec:
    """One flight mode of an autopilot."""

    name: str
    custom_mode: int
    """HEARTBEAT.custom_mode as the real autopilot encodes it."""
    behaviour: Behaviour
    armable: bool = True
    """Whether the vehicle may arm in this mode."""


@dataclass(frozen=True)
class TakeoffRequest:
    """A takeoff the persona accepted: climb to ``altitude`` metres above home."""

    altitude: float
    mode: ModeSpec | None
    """Mode to switch to for the climb, or None to climb in the current mode."""
    note: str = ""
    """STATUSTEXT to send with the acceptance (PX4: the minimum altitude was used)."""


@dataclass(frozen=True)
class VehicleFacts:
    """What a persona may look at when it judges a command."""

    armed: bool
    landed: bool
    mode: ModeSpec
    home_alt_amsl: float
    setpoint_age: float
    """Sim seconds since the last position/velocity setpoint (inf if none)."""


@dataclass(frozen=True)
class ProfileFacts:
    """The profile values that set parameter defaults."""

    speed: float
    tau: float
    sensor_radii: tuple[float, ...]
    system_id: int
    timeout_scale: float = 1.0
    """Multiplier on time-out defaults so wall-clock clients keep working at speed-ups."""
    battery_endurance: float = 7200.0


def common_params(facts: ProfileFacts) -> list[ParamSpec]:
    """The emulator's own parameters, the same on every persona."""
    n = len(facts.sensor_radii)
    specs = [
        ParamSpec(
            "MDM_SENSOR", -1, ParamType.INT32, -1, n - 1, "active sensor index, -1 = all off"
        ),
        ParamSpec("MDM_FENCE_MARG", 100.0, low=0.0, doc="geofence margin around the area, m"),
        ParamSpec(
            "MDM_BAT_ENDUR",
            facts.battery_endurance,
            low=1.0,
            doc="flight time from full battery, sim s",
        ),
        ParamSpec(
            "MDM_TAU",
            facts.tau,
            low=facts.tau,
            high=facts.tau,
            doc="velocity-loop tau, s (read-only)",
        ),
    ]
    specs += [
        ParamSpec(f"MDM_SENS_R{i}", r, low=1e-3, doc=f"radius of sensor {i}, m")
        for i, r in enumerate(facts.sensor_radii)
    ]
    return specs


class Persona(ABC):
    """An autopilot's outward behaviour. Subclasses fill the class variables and the hooks."""

    name: ClassVar[str]
    autopilot: ClassVar[int]
    """MAV_AUTOPILOT value in HEARTBEAT."""
    bytewise_ints: ClassVar[bool]
    modes: ClassVar[tuple[ModeSpec, ...]]
    default_mode: ClassVar[str]
    external_mode: ClassVar[str]
    hold_mode: ClassVar[str]
    rtl_mode: ClassVar[str]
    land_mode: ClassVar[str]
    position_mode: ClassVar[str | None] = None
    """The mode of Action.POSITION; None: the hold mode."""
    offboard_needs_setpoints: ClassVar[bool]
    """PX4 refuses OFFBOARD unless setpoints are streaming."""
    position_targets_time_out: ClassVar[bool]
    """PX4 times out every setpoint; ArduPilot only velocity targets."""
    takeoff_while_disarmed: ClassVar[bool]
    """PX4 accepts NAV_TAKEOFF (and TAKEOFF mode) disarmed and climbs once armed."""
    takeoff_refusal: ClassVar[int]
    """MAV_RESULT of a refused takeoff."""
    reposition_mode: ClassVar[str]
    """Mode MAV_CMD_DO_REPOSITION flies in."""
    mode_after_landing: ClassVar[str | None] = None
    """Mode a landing that disarmed switches to (PX4: HOLD, measured on PX4 SITL)."""
    reposition_elsewhere: ClassVar[int]
    """MAV_RESULT of a DO_REPOSITION outside that mode without the mode-change flag."""
    mission: ClassVar[MissionRules]
    """The mission protocol's answers and AUTO's behaviour."""
    mission_mode: ClassVar[str]
    """The mode that flies the stored mission (AUTO, MISSION)."""
    capabilities: ClassVar[int]
    """AUTOPILOT_VERSION.capabilities: the real autopilot's bits less what the emulator lacks."""
    firmware_version: ClassVar[int]
    """AUTOPILOT_VERSION.flight_sw_version (major<<24 | minor<<16 | patch<<8 | type)."""
    unknown_mode_result: ClassVar[int]
    """MAV_RESULT of DO_SET_MODE naming a mode the autopilot does not have."""
    manual_modes: ClassVar[frozenset[str]]
    """Modes in which pilot sticks (MANUAL_CONTROL, RC_CHANNELS_OVERRIDE) fly the vehicle."""
    data_streams: ClassVar[bool]
    flight_commands: ClassVar[frozenset[int]]
    """Which of flight_commands.MISSION_COMMANDS the autopilot takes (others UNSUPPORTED)."""
    fence_enable_param: ClassVar[str] = ""
    """The parameter DO_FENCE_ENABLE sets."""
    loiter_mode: ClassVar[str] = ""
    """The mode a NAV_LOITER_UNLIM command switches to."""
    fixed_intervals: ClassVar[frozenset[int]] = frozenset()
    """Message ids whose SET_MESSAGE_INTERVAL the autopilot answers FAILED (PX4)."""
    unrequestable: ClassVar[frozenset[int]] = frozenset()
    """Message ids REQUEST_MESSAGE is DENIED for although the autopilot streams them (PX4)."""
    """REQUEST_DATA_STREAM sets stream rates (ArduPilot) or is ignored (PX4)."""

    def mode(self, name: str) -> ModeSpec:
        for m in self.modes:
            if m.name == name:
                return m
        raise KeyError(name)

    def mode_by_custom(self, custom_mode: int) -> ModeSpec | None:
        for m in self.modes:
            if m.custom_mode == custom_mode:
                return m
        return None

    def mode_for(self, action: Action) -> ModeSpec | None:
        names = {
            Action.HOLD: self.hold_mode,
            Action.POSITION: self.position_mode or self.hold_mode,
            Action.RTL: self.rtl_mode,
            Action.LAND: self.land_mode,
        }
        return self.mode(names[action]) if action in names else None

    def param_table(self, facts: ProfileFacts) -> ParamTable:
        return ParamTable(
            self.param_specs(facts) + common_params(facts), bytewise_ints=self.bytewise_ints
        )

    @staticmethod
    def _finite(x: float) -> bool:
        return math.isfinite(x)

    @abstractmethod
    def param_specs(self, facts: ProfileFacts) -> list[ParamSpec]:
        """The persona's own parameters (failsafes, fence, speeds)."""

    @abstractmethod
    def mode_from_command(self, p1: float, p2: float, p3: float) -> ModeSpec | None:
        """MAV_CMD_DO_SET_MODE parameters to a mode (None: not a mode of this autopilot)."""

    @abstractmethod
    def takeoff(self, p7: float, params: ParamTable, vehicle: VehicleFacts) -> TakeoffRequest | str:
        """Judge MAV_CMD_NAV_TAKEOFF; a string is the reason for refusing it."""

    @abstractmethod
    def after_takeoff(self) -> ModeSpec | None:
        """Mode once the takeoff altitude is reached (None: stay in the current mode)."""

    @abstractmethod
    def setpoint_loss(self, params: ParamTable) -> tuple[float, Action]:
        """Time-out (sim s) of the setpoint stream in EXTERNAL mode, and the reaction."""

    @abstractmethod
    def link_loss(self, params: ParamTable) -> tuple[float, Action]:
        """Time-out (sim s) of the companion/GCS heartbeat and the reaction."""

    def watches_heartbeat(self, params: ParamTable, sysid: int) -> bool:
        """Whether a GCS or companion HEARTBEAT from system ``sysid`` is the one the link-loss
        failsafe watches (PX4: any)."""
        return True

    @abstractmethod
    def fence_action(self, params: ParamTable) -> Action:
        """Reaction to leaving the search area plus margin."""

    @abstractmethod
    def fence_rules(self, params: ParamTable) -> FenceRules | None:
        """The vehicle's own fences (altitude, radius, uploaded shapes); None: all off."""

    reports_geofence: ClassVar[bool] = False
    """SYS_STATUS carries the geofence sensor bit (ArduPilot) or not (PX4)."""

    @abstractmethod
    def low_battery(self, params: ParamTable) -> tuple[float, Action]:
        """Remaining fraction below which the reaction fires."""

    @abstractmethod
    def speeds(self, params: ParamTable) -> tuple[float, float, float, float]:
        """Horizontal speed, climb rate, descent rate and landing speed, m/s."""

    @abstractmethod
    def mission_speed(self, params: ParamTable) -> float:
        """Horizontal speed between mission waypoints, m/s."""

    @abstractmethod
    def speed_limits(self, params: ParamTable) -> tuple[float, float, float, float]:
        """The most MAV_CMD_DO_CHANGE_SPEED may set: horizontal, climb, descent, landing."""

    def takeoff_climb(self, params: ParamTable) -> float | None:
        """Climb rate of a takeoff, m/s (None: the ordinary climb limit)."""
        return None

    def default_takeoff_alt(self, params: ParamTable) -> float:
        """Height a TAKEOFF mode entered without a takeoff command climbs to, m."""
        return params.get("MIS_TAKEOFF_ALT") if "MIS_TAKEOFF_ALT" in params else 2.5

    @abstractmethod
    def stick_timeout(self, params: ParamTable) -> float:
        """Sim s without MANUAL_CONTROL / RC override after which the sticks are released."""

    def orbit_entered(self, params: ParamTable, north: float, east: float, yaw: float) -> Orbit:
        """The circle flown when the orbit mode is entered without a DO_ORBIT."""
        return orbit_about(north, east, (north - 10.0, east), 10.0, 1.0)

    @abstractmethod
    def rtl_altitude(self, params: ParamTable) -> float:
        """Altitude above home for the return leg, m."""
