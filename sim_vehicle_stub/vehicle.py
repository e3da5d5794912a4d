"""One vehicle's autopilot logic: modes, arming, takeoff, setpoints; the persona decides details."""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from sim_vehicle_stub.config import system_id
from sim_vehicle_stub.events import EventLog
from sim_vehicle_stub.fence_enforcement import FenceRules, FenceShapes
from sim_vehicle_stub.fleet_kinematics import Fleet
from sim_vehicle_stub.fleet_step_kernel import GROUND_ALT
from sim_vehicle_stub.geo_frame import GeoFrame
from sim_vehicle_stub.manual_control import Pilot, fly_sticks
from sim_vehicle_stub.mission_flight import MissionRun, return_point
from sim_vehicle_stub.mission_store import MissionItem, VehiclePlans
from sim_vehicle_stub.orbit import Orbit
from sim_vehicle_stub.params import ParamTable
from sim_vehicle_stub.personas.base import (
    Action,
    Behaviour,
    ModeSpec,
    Persona,
    TakeoffRequest,
    VehicleFacts,
)

log = logging.getLogger(__name__)

# MAV_RESULT values.
ACCEPTED, TEMPORARILY_REJECTED, DENIED, UNSUPPORTED, FAILED = 0, 1, 2, 3, 4


@dataclass(frozen=True)
class FailsafeLimits:
    """The persona's failsafe choices for the current parameters (re-read on PARAM_SET)."""

    setpoint: tuple[float, Action]
    link: tuple[float, Action]
    fence: Action
    fence_rules: FenceRules | None
    """The vehicle's own fences besides the area (fence_enforcement.py)."""
    battery: tuple[float, Action]
    endurance: float
    fence_margin: float
    sticks: float
    """Sim s after the last MANUAL_CONTROL / RC override before the sticks count as released."""
    sensor: int
    """MDM_SENSOR: active sensor index, -1 when off."""


@dataclass
class NeuSetpoint:
    """The last SET_POSITION_TARGET_* received, in the local frame (north, east, up)."""

    t: float
    position: tuple[float, float] | None
    velocity: tuple[float, float] | None
    alt: float | None
    climb: float | None
    yaw: float | None
    yaw_rate: float | None = None
    accel: tuple[float, float, float] | None = None
    """Acceleration-only target (north, east, up), m/s^2: integrated into a velocity."""


class Vehicle:
    """Mode machine of vehicle ``index``; motion is written to the shared :class:`Fleet`."""

    def __init__(
        self,
        index: int,
        persona: Persona,
        params: ParamTable,
        fleet: Fleet,
        events: EventLog,
        now: Callable[[], float],
        geo: GeoFrame,
    ) -> None:
        self.index = index
        self.geo = geo
        self.sysid = system_id(index)
        self.persona = persona
        self.params = params
        self.fleet = fleet
        self.events = events
        self._now = now
        self.origin: tuple[float, float] = (float(fleet.pos[index, 0]), float(fleet.pos[index, 1]))
        """The local frame's origin in the profile's frame: where the vehicle booted (the EKF
        origin of a real autopilot). LOCAL_POSITION_NED and local setpoints are metres from it."""
        self.home: tuple[float, float] = self.origin
        """Where RTL returns to (DO_SET_HOME moves it; the local origin stays)."""
        self.plans = VehiclePlans()
        if persona.mission.home_is_item0:  # ArduPilot boots with home as its one item
            self.plans.mission.items = [MissionItem(16, 0, (0.0, 0.0, 0.0, 0.0), 0, 0, 0.0)]
        self.mission_run = MissionRun(self)
        self.outbox: list[Any] = []
        """Messages waiting to be sent with the next tick (MISSION_CURRENT, ITEM_REACHED)."""
        self.pilot = Pilot()
        self.orbit: Orbit | None = None
        """The circle being flown in the orbit mode (CIRCLE, ORBIT)."""
        self._orbit_t = 0.0
        self.fence_shapes = FenceShapes()
        """The uploaded fence in the local frame, rebuilt when a new one is stored."""
        self.auto_armed = False
        """ArduCopter's auto_armed: AUTO may leave the ground (set by a takeoff, MISSION_START
        or throttle; cleared on disarming)."""
        self.mode: ModeSpec = persona.mode(persona.default_mode)
        self.armed = False
        self.setpoint: NeuSetpoint | None = None
        self.setpoint_lost = False
        self.takeoff_alt: float | None = None
        self.pending_takeoff: float | None = None
        """Altitude of a takeoff accepted while disarmed (PX4), flown once armed."""
        self.rtl_phase = 0
        self.rtl_target: tuple[float, float] = self.home
        """Where the RTL in progress lands: home or the nearest rally point."""
        self.last_gcs_heartbeat: float | None = None
        self.link_lost = False
        self.fence_breached = False
        self.battery = 1.0
        self.battery_fired = False
        self.state_changed = True
        """Set on any mode/arm change so an extra HEARTBEAT goes out."""
        self.status: list[tuple[int, str]] = []
        """STATUSTEXT (severity, text) waiting to be sent."""
        self.limits: FailsafeLimits
        self.climb_limit = 0.0
        """Climb rate limit outside takeoffs, m/s (parameters, DO_CHANGE_SPEED)."""
        self.apply_params()

    # ----- facts
    @property
    def now(self) -> float:
        return self._now()

    @property
    def landed(self) -> bool:
        i = self.index
        return bool(self.fleet.alt[i] <= GROUND_ALT and self.fleet.vz[i] <= 0.05)

    def facts(self, home_alt_amsl: float) -> VehicleFacts:
        age = self.now - self.setpoint.t if self.setpoint else math.inf
        return VehicleFacts(self.armed, self.landed, self.mode, home_alt_amsl, age)

    def apply_params(self) -> None:
        """Re-read the parameters the dynamics and failsafes use (after any PARAM_SET)."""
        p, params = self.persona, self.params
        speed, climb, descent, _ = p.speeds(params)
        i = self.index
        self.fleet.speed[i], self.fleet.climb[i], self.fleet.descent[i] = speed, climb, descent
        self.climb_limit = climb
        self.limits = FailsafeLimits(
            setpoint=p.setpoint_loss(params),
            link=p.link_loss(params),
            fence=p.fence_action(params),
            fence_rules=p.fence_rules(params),
            battery=p.low_battery(params),
            endurance=params.get("MDM_BAT_ENDUR"),
            fence_margin=params.get("MDM_FENCE_MARG"),
            sticks=p.stick_timeout(params),
            sensor=int(params.get("MDM_SENSOR")),
        )

    def sensor_radius(self) -> float:
        """Radius of the active sensor (of sensor 0 when all are off)."""
        return self.params.get(f"MDM_SENS_R{max(self.limits.sensor, 0)}")

    def say(self, severity: int, text: str) -> None:
        self.status.append((severity, text[:50]))

    # ----- modes and arming
    def set_mode(self, mode: ModeSpec, reason: str = "command") -> int:
        """Switch to ``mode``; returns a MAV_RESULT."""
        p = self.persona
        if mode.behaviour is Behaviour.EXTERNAL and p.offboard_needs_setpoints:
            timeout, _ = self.limits.setpoint
            if self.setpoint is None or self.now - self.setpoint.t > timeout:
                self.say(4, f"{mode.name} refused: no setpoints")
                return DENIED
        if mode.behaviour in (Behaviour.RTL, Behaviour.LAND) and not self.armed:
            return DENIED
        if mode.behaviour is Behaviour.TAKEOFF and not (self.armed or p.takeoff_while_disarmed):
            return DENIED
        if mode.behaviour is Behaviour.MISSION and (refusal := self._mission_refusal()):
            self.say(4, refusal)
            return DENIED
        if mode == self.mode:
            return ACCEPTED
        if self.mode.behaviour is Behaviour.MISSION:
            self.mission_run.leave()
        if mode.behaviour is not Behaviour.ORBIT:
            self.orbit = None
        self.mode = mode
        self.state_changed = True
        self.events.write(self.now, "mode", vehicle=self.index, mode=mode.name, reason=reason)
        self._enter(mode)
        return ACCEPTED

    def _mission_refusal(self) -> str:
        """Why the mission mode cannot be entered now ('' when it can): ArduCopter armed on
        the ground needs a NAV_TAKEOFF first (ModeAuto::init)."""
        rules = self.persona.mission
        if rules.takeoff_when_landed or not (self.armed and self.landed):
            return ""
        items = self.mission_run.items[self.mission_run.first :]
        if items and items[0].command == 22:  # MAV_CMD_NAV_TAKEOFF
            return ""
        return "Auto: Missing Takeoff Cmd"

    def _enter(self, mode: ModeSpec) -> None:
        i, f = self.index, self.fleet
        b = mode.behaviour
        self.takeoff_alt = None
        f.yaw_cmd[i] = np.nan
        f.yaw_rate[i] = np.nan
        if not self.armed:
            # Motors off: a mode change moves nothing (PX4 accepts OFFBOARD or TAKEOFF while
            # disarmed and acts on them once armed, see arm()).
            return
        if b is Behaviour.EXTERNAL:
            f.hold(i)
            self.setpoint_lost = False
            if self.setpoint is not None and self.persona.offboard_needs_setpoints:
                self._apply(self.setpoint)
        elif b is Behaviour.TAKEOFF:
            f.hold(i)
            self.takeoff_alt = self.pending_takeoff or self.persona.default_takeoff_alt(self.params)
            self.pending_takeoff = None
            f.climb_to(i, self.takeoff_alt)
            self._climb_cap()
        elif b is Behaviour.LAND:
            f.hold(i)
            f.climb_rate(i, -self.persona.speeds(self.params)[3])
        elif b is Behaviour.MISSION:
            f.hold(i)
            self.mission_run.enter()
        elif b is Behaviour.ORBIT:
            f.hold(i)
            if self.orbit is None:
                self.orbit = self.persona.orbit_entered(
                    self.params, float(f.pos[i, 0]), float(f.pos[i, 1]), float(f.yaw[i])
                )
            self._orbit_t = self.now
        elif b is Behaviour.RTL:
            f.hold(i)
            self.rtl_phase = 0
            f.climb_to(i, max(float(f.alt[i]), self.persona.rtl_altitude(self.params)))
        else:
            f.hold(i)

    def arm(self, arm: bool, *, force: bool = False) -> int:
        if arm == self.armed:
            return ACCEPTED
        if arm:
            if not self.mode.armable or not self.landed:
                return DENIED
        elif not (self.landed or force):
            return DENIED
        self.armed = arm
        self.auto_armed = False
        self.state_changed = True
        self.battery_fired = False
        self.events.write(self.now, "armed" if arm else "disarmed", vehicle=self.index)
        if arm:
            self._enter(self.mode)  # an OFFBOARD setpoint or a TAKEOFF waiting for the motors
        else:
            self._fall()
        return ACCEPTED

    def _fall(self) -> None:
        """Motors stopped: no horizontal control, down to the ground (a real copter drops;
        here it sinks at the persona's maximum descent rate, so it lands and can re-arm)."""
        i, f = self.index, self.fleet
        self.takeoff_alt = None
        f.hold(i)
        f.fly_velocity(i, 0.0, 0.0)
        f.climb_rate(i, -float(f.descent[i]))

    def takeoff(self, p7: float, home_alt_amsl: float) -> int:
        req = self.persona.takeoff(p7, self.params, self.facts(home_alt_amsl))
        if not isinstance(req, TakeoffRequest):
            self.say(4, f"takeoff refused: {req}")
            return self.persona.takeoff_refusal
        if req.note:
            self.say(4, req.note)
        if not self.armed:
            self.pending_takeoff = req.altitude
        if req.mode is not None:
            result = self.set_mode(req.mode, "takeoff")
            if result != ACCEPTED:
                return result
        if self.armed:
            self.auto_armed = True
            self.takeoff_alt = req.altitude
            self.fleet.hold(self.index)
            self.fleet.climb_to(self.index, req.altitude)
            self._climb_cap()
        return ACCEPTED

    def change_speed(self, kind: float, speed: float) -> int:
        """MAV_CMD_DO_CHANGE_SPEED: ground speed (kind 0/1), climb (2) or descent (3) rate,
        capped at what the persona's vehicle can fly."""
        # ArduCopter GCS_MAVLink_Copter.cpp handle_MAV_CMD_DO_CHANGE_SPEED: a speed that is
        # not positive, or an unknown speed type, is DENIED.
        if not (math.isfinite(speed) and speed > 0) or kind not in (0, 1, 2, 3):
            return DENIED
        i, f = self.index, self.fleet
        top, climb, descent, _ = self.persona.speed_limits(self.params)
        if kind in (0, 1):
            f.speed[i] = min(speed, top)
        elif kind == 2:
            self.climb_limit = f.climb[i] = min(speed, climb)
        else:
            f.descent[i] = min(speed, descent)
        return ACCEPTED

    def reposition(self, north: float, east: float, alt: float | None, change_mode: bool) -> int:
        """MAV_CMD_DO_REPOSITION to a point of the local frame (alt above home, None: keep)."""
        p = self.persona
        target = p.mode(p.reposition_mode)
        if self.mode != target and not change_mode:
            return p.reposition_elsewhere
        result = self.set_mode(target, "reposition")
        if result != ACCEPTED or not self.armed or self.landed:
            return result  # PX4 switches mode but moves nothing on the ground
        if target.behaviour is Behaviour.EXTERNAL:
            self.setpoint = NeuSetpoint(self.now, (north, east), None, alt, None, None)
            self._apply(self.setpoint)
        else:
            self.fleet.go_to(self.index, north, east)
            if alt is not None:
                self.fleet.climb_to(self.index, alt)
        return ACCEPTED

    def failsafe(self, action: Action, why: str) -> None:
        """Carry out a failsafe reaction (no-op for Action.NONE)."""
        mode = self.persona.mode_for(action)
        if mode is None or not self.armed:
            return
        self.say(2, f"Failsafe: {why}, {mode.name}")
        self.events.write(self.now, "failsafe", vehicle=self.index, cause=why, action=mode.name)
        log.info("vehicle %d failsafe %s -> %s", self.index, why, mode.name)
        if mode == self.mode:
            self._enter(mode)
        else:
            self.set_mode(mode, why)

    # ----- setpoints
    def on_setpoint(self, sp: NeuSetpoint) -> None:
        """A decoded setpoint; PX4 records it in any mode, ArduPilot only in GUIDED."""
        external = self.mode.behaviour is Behaviour.EXTERNAL
        if not external and not self.persona.offboard_needs_setpoints:
            return
        self.setpoint = sp
        self.setpoint_lost = False
        if external and self.armed:
            self._apply(sp)

    def _apply(self, sp: NeuSetpoint) -> None:
        i, f = self.index, self.fleet
        f.h_acc[i] = 0.0
        f.v_acc[i] = 0.0
        if sp.position is not None:
            f.go_to(i, *sp.position)
        elif sp.velocity is not None:
            f.fly_velocity(i, *sp.velocity)
        elif sp.accel is not None:
            # ArduCopter ModeGuided::set_accel: the vehicle follows an acceleration alone;
            # integrated here from the current velocity into the lag loop's reference.
            f.fly_velocity(i, *f.vel[i])
            f.h_acc[i] = sp.accel[:2]
        if sp.alt is not None:
            f.climb_to(i, sp.alt)
        elif sp.climb is not None:
            f.climb_rate(i, sp.climb)
        elif sp.accel is not None:
            f.climb_rate(i, float(f.vz[i]))
            f.v_acc[i] = sp.accel[2]
        if sp.yaw is not None:
            f.yaw_cmd[i], f.yaw_rate[i] = sp.yaw, np.nan
        elif sp.yaw_rate is not None:
            f.yaw_cmd[i], f.yaw_rate[i] = np.nan, sp.yaw_rate
        if sp.alt is not None or sp.climb is not None or sp.accel is not None:
            self.takeoff_alt = None

    # ----- per tick
    def _climb_cap(self) -> None:
        """The climb rate limit: the persona's takeoff speed while a takeoff climbs."""
        tko = self.persona.takeoff_climb(self.params)
        climbing = self.takeoff_alt is not None and tko is not None
        self.fleet.climb[self.index] = tko if climbing and tko is not None else self.climb_limit

    def update(self) -> None:
        """Mode phases that end on their own: takeoff reached, RTL legs, touchdown."""
        i, f = self.index, self.fleet
        b = self.mode.behaviour
        self._climb_cap()
        if self.takeoff_alt is not None and f.alt[i] >= self.takeoff_alt - 0.3:
            self.takeoff_alt = None
            nxt = self.persona.after_takeoff()
            if nxt is not None and b is Behaviour.TAKEOFF:
                self.set_mode(nxt, "takeoff complete")
        if b is Behaviour.RTL:
            self._rtl_step()
        elif b is Behaviour.MISSION:
            self.mission_run.step()
        elif b is Behaviour.ORBIT and self.orbit is not None and self.armed and not self.landed:
            now = self.now
            f.go_to(i, *self.orbit.advance(now - self._orbit_t))
            self._orbit_t = now
        if self.mode.name in self.persona.manual_modes:
            fly_sticks(self)
        touching = self.armed and f.alt[i] <= 0.05
        ending = b is Behaviour.MISSION and self.mission_run.landing
        if touching and ending:
            self.mission_run.touched_down()
        if touching and (
            ending or b is Behaviour.LAND or (b is Behaviour.RTL and self.rtl_phase == 2)
        ):
            self.arm(False, force=True)
            self.say(6, "Landed, disarmed")
            after = self.persona.mode_after_landing
            if after is not None:
                self.set_mode(self.persona.mode(after), "landed")

    def _rtl_step(self) -> None:
        i, f = self.index, self.fleet
        if self.rtl_phase == 0 and f.alt[i] >= f.v_target[i] - 0.5:
            self.rtl_phase = 1
            self.rtl_target = return_point(self)
            f.go_to(i, *self.rtl_target)
        elif self.rtl_phase == 1 and np.hypot(*(f.pos[i] - self.rtl_target)) < 1.0:
            self.rtl_phase = 2
            f.climb_rate(i, -self.persona.speeds(self.params)[3])
