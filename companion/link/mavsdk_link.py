"""The MAVSDK 4 backend (native library): actions, offboard and params through MAVSDK's plugins.

Readings MAVSDK has no plugin for (DEBUG_VECT, NAMED_VALUE_FLOAT) and the raw HEARTBEAT /
LOCAL_POSITION_NED with the vehicle's time_boot_ms come through the MavlinkDirect plugin.
MAVSDK sends its own heartbeat as well as ours (its library thread does that by design);
the decision loop's heartbeat still goes out through MavlinkDirect.
"""

from __future__ import annotations

import asyncio
import json
import logging
import math
import time
from pathlib import Path
from typing import Any

from mavsdk.asyncio import Configuration, Mavsdk
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.offboard import OffboardAsync
from mavsdk.asyncio.plugins.param import ParamAsync
from mavsdk.plugins.mavlink_direct import MavlinkDirect, MavlinkMessage
from mavsdk.plugins.offboard import Offboard, PositionNedYaw, VelocityNedYaw
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.autopilots import FlightMode, UnknownAutopilotError, autopilot_for
from companion.guidance import NedSetpoint
from companion.link.address import parse_address
from companion.link.base import LinkError, SetpointKind, VehicleLink
from companion.link.log_transfer import FlightLog
from companion.link.mavsdk_logs import download_newest
from companion.link.messages import (
    Heartbeat,
    LinkEvent,
    SensorContact,
    SensorSignal,
    StatusText,
    SystemStatus,
)
from companion.link.outcome import CommandResult, accepted, denied, timed_out
from companion.link.tlog import TelemetryLog

log = logging.getLogger(__name__)
_SUBSCRIBED = (
    "HEARTBEAT",
    "LOCAL_POSITION_NED",
    "SYS_STATUS",
    "DEBUG_VECT",
    "NAMED_VALUE_FLOAT",
    "STATUSTEXT",
    "GLOBAL_POSITION_INT",
    "GPS_GLOBAL_ORIGIN",
    "HOME_POSITION",
)
_INTEGER_TYPES = (
    mavlink2.MAV_PARAM_TYPE_INT8,
    mavlink2.MAV_PARAM_TYPE_INT16,
    mavlink2.MAV_PARAM_TYPE_INT32,
)
"""Parameter types set with the plugin's set_param_int first."""
_HEALTH_BITS = mavlink2.MAV_SYS_STATUS_SENSOR_GPS | mavlink2.MAV_SYS_STATUS_PREARM_CHECK
_NOT_AUTOPILOT_TYPES = (
    mavlink2.MAV_TYPE_GCS,
    mavlink2.MAV_TYPE_ONBOARD_CONTROLLER,
    mavlink2.MAV_TYPE_GIMBAL,
    mavlink2.MAV_TYPE_ADSB,
)


class MavsdkLink(VehicleLink):
    """A vehicle over MAVSDK.

    Args:
        url: as for the pymavlink backend (udpin/udpout/tcp); converted to MAVSDK's spelling.
        target_system: the vehicle's system id.
        system_id / component_id: the companion's own ids (not 1: that is vehicle 1).
        tlog: .tlog path; holds the subscribed messages (MAVSDK does not hand out raw bytes).
        discover_timeout: wall seconds per wait for the vehicle's first heartbeat.
    """

    def __init__(
        self,
        *,
        url: str,
        target_system: int,
        system_id: int = 245,
        component_id: int = 191,
        tlog: Path | None = None,
        discover_timeout: float = 5.0,
    ) -> None:
        super().__init__()
        self.address = parse_address(url)
        self.target_system = target_system
        self._ids = (system_id, component_id)
        self.own_system = system_id
        self._tlog_path = tlog
        self._tlog: TelemetryLog | None = None
        self._discover_timeout = discover_timeout
        self._mavsdk: Mavsdk | None = None
        self._system: Any = None
        self._direct: MavlinkDirect | None = None
        self._offboard_sync: Offboard | None = None
        self._action: ActionAsync | None = None
        self._offboard: OffboardAsync | None = None
        self._param: ParamAsync | None = None
        self._handles: list[Any] = []
        self._loop: asyncio.AbstractEventLoop | None = None
        self._offboard_started = False
        self._airborne = False
        """begin_setpoints ran: on ArduPilot, GUIDED is entered through Offboard from now on."""

    def describe(self) -> str:
        return self.address.url()

    async def open(self) -> None:
        if self._mavsdk is not None:
            return
        self._loop = asyncio.get_running_loop()
        if self._tlog_path is not None:
            self._tlog = TelemetryLog(self._tlog_path)
        cfg = Configuration.create_manual(*self._ids, False)
        self._mavsdk = Mavsdk(cfg)
        try:
            await self._mavsdk.add_any_connection(self.address.mavsdk_url())
        except Exception as exc:  # MAVSDK's ConnectionError: tcp not up yet and the like
            self._mavsdk.destroy()
            self._mavsdk = None
            raise LinkError(f"cannot open {self.address.url()}: {exc}") from exc
        system = None
        while system is None:
            system = await self._mavsdk.first_autopilot(timeout_s=self._discover_timeout)
            if system is None:
                log.warning(
                    "MAVSDK: waiting for system %d on %s; no autopilot heard yet",
                    self.target_system,
                    self.address.url(),
                )
        self._system = system
        raw = system._system
        self._direct = MavlinkDirect(raw)
        self._action = ActionAsync(system)
        self._offboard = OffboardAsync(system)
        # the async wrapper's own plugin: offboard.start() checks that a setpoint was set on it
        self._offboard_sync = self._offboard._plugin
        self._param = ParamAsync(system)
        for name in _SUBSCRIBED:
            self._handles.append(self._direct.subscribe_message(name, self._from_thread))
        log.info("MAVSDK link to system %d on %s", self.target_system, self.address.mavsdk_url())

    async def close(self) -> None:
        if self._direct is not None:
            for handle in self._handles:
                self._direct.unsubscribe_message(handle)
        self._handles.clear()
        if self._mavsdk is not None:
            self._mavsdk.destroy()
        self._mavsdk = self._direct = self._offboard_sync = self._system = None
        self._action = self._offboard = self._param = None
        self._offboard_started = False
        if self._tlog is not None:
            self._tlog.close()
            self._tlog = None

    async def reconnect(self) -> None:
        """MAVSDK re-discovers a system that speaks again by itself: nothing to do."""

    # -- receiving -------------------------------------------------------------------------

    def _from_thread(self, message: MavlinkMessage, _user: object) -> None:
        loop = self._loop
        if loop is not None and not loop.is_closed():
            loop.call_soon_threadsafe(self._receive, message, time.perf_counter())

    def _receive(self, message: MavlinkMessage, received: float) -> None:
        self.heard.add(message.system_id)
        if message.system_id != self.target_system:
            return
        try:
            fields = json.loads(message.fields_json)
            event = self._translate(message.message_name, message.component_id, fields, received)
        except (ValueError, KeyError, TypeError, UnknownAutopilotError) as exc:
            self.guard.unreadable(message.message_name, exc)
            return
        if self._tlog is not None:
            self._tlog.write(_repack(message.message_name, fields, self.target_system))
        if event is not None:
            self.publish([event])

    def _translate(
        self, name: str, component: int, f: dict[str, Any], received: float
    ) -> LinkEvent | None:
        if name == "LOCAL_POSITION_NED":
            self.streams.note(name, f["time_boot_ms"] / 1000.0)
            return self._local(
                component,
                f["time_boot_ms"] / 1000.0,
                _number(f["x"]),
                _number(f["y"]),
                _number(f["z"]),
                _number(f["vx"]),
                _number(f["vy"]),
                _number(f["vz"]),
                received,
            )
        if name == "GLOBAL_POSITION_INT":
            return self._global(
                component,
                f["time_boot_ms"] / 1000.0,
                f["lat"] * 1e-7,
                f["lon"] * 1e-7,
                f["relative_alt"] * 1e-3,
            )
        if name == "GPS_GLOBAL_ORIGIN":
            self._note_origin(f["latitude"] * 1e-7, f["longitude"] * 1e-7, f["altitude"] * 1e-3)
            return None
        if name == "HOME_POSITION":
            self._note_home(
                f["latitude"] * 1e-7, f["longitude"] * 1e-7, f["altitude"] * 1e-3, f["x"], f["y"]
            )
            return None
        if name == "DEBUG_VECT":
            label = str(f["name"]).rstrip("\x00")
            reading = (f["time_usec"], _number(f["x"]), _number(f["y"]), _number(f["z"]))
            if label in ("DET", "CNF") and self.guard.reading(*reading):
                north, east = self._profile_xy(reading[1], reading[2])
                return SensorContact(label, reading[0] / 1e6, north, east, reading[3])
            return None
        if name == "NAMED_VALUE_FLOAT":
            value = _number(f["value"])
            if str(f["name"]).rstrip("\x00") == "SENS_SIG" and self.guard.reading(
                f["time_boot_ms"], value
            ):
                return SensorSignal(f["time_boot_ms"] / 1000.0, value)
            return None
        if name == "HEARTBEAT":
            if component != 1 or f["type"] in _NOT_AUTOPILOT_TYPES:
                return None
            if self.autopilot is None or self.autopilot.mav_autopilot != f["autopilot"]:
                self.autopilot = autopilot_for(int(f["autopilot"]))
            return Heartbeat(
                int(f["autopilot"]),
                int(f["custom_mode"]),
                bool(f["base_mode"] & 128),
                int(f["system_status"]),
            )
        if name == "STATUSTEXT":
            text = str(f["text"]).rstrip("\x00")
            self._note_text(int(f["severity"]), text)
            return StatusText(int(f["severity"]), text)
        if name == "SYS_STATUS":
            self.streams.note(name)
            need = f["onboard_control_sensors_present"] & _HEALTH_BITS
            healthy = (f["onboard_control_sensors_health"] & need) == need
            return SystemStatus(int(f["battery_remaining"]), healthy)
        return None

    # -- sending ---------------------------------------------------------------------------

    def send_heartbeat(self) -> None:
        if self._direct is None:
            return
        fields = {
            "type": mavlink2.MAV_TYPE_ONBOARD_CONTROLLER,
            "autopilot": mavlink2.MAV_AUTOPILOT_INVALID,
            "base_mode": 0,
            "custom_mode": 0,
            "system_status": mavlink2.MAV_STATE_ACTIVE,
            "mavlink_version": 3,
        }
        msg = MavlinkMessage("HEARTBEAT", *self._ids, 0, 0, json.dumps(fields))
        try:
            self._direct.send_message(msg)
        except Exception as exc:  # MAVSDK raises its own error types; never crash the loop
            log.debug("heartbeat not sent: %s", exc)

    def send_setpoint(self, setpoint: NedSetpoint, kind: SetpointKind) -> None:
        off = self._offboard_sync
        if off is None or (self._ardupilot() and not self._offboard_started):
            # MAVSDK repeats the last setpoint at 20 Hz from the first one set, and a velocity
            # setpoint during an ArduCopter takeoff cancels it: none before begin_setpoints.
            return
        sp = setpoint
        try:
            if kind == "velocity":
                off.set_velocity_ned(VelocityNedYaw(sp.vn, sp.ve, sp.vd, 0.0))
            else:
                north, east = self._vehicle_xy(sp.north, sp.east)
                off.set_position_ned(PositionNedYaw(north, east, sp.down, 0.0))
        except Exception as exc:
            log.debug("setpoint not sent: %s", exc)

    def _ardupilot(self) -> bool:
        return self.autopilot is not None and self.autopilot.name == "ardupilot"

    async def set_mode(self, mode: FlightMode) -> CommandResult:
        if self._action is None or self._offboard is None:
            raise LinkError("set_mode before the vehicle was discovered")
        if mode is FlightMode.GUIDED and self._ardupilot() and not self._airborne:
            # GUIDED without Offboard: takeoff first (begin_setpoints starts Offboard after it).
            assert self.autopilot is not None
            cmd = self.autopilot.mode_command(mode, armed=False)
            return await self.command_long(
                mavlink2.MAV_CMD_DO_SET_MODE, cmd.base_mode, cmd.custom_main, cmd.custom_sub
            )
        since = time.monotonic()
        try:
            if mode is FlightMode.GUIDED:
                await self._start_offboard()
            elif mode is FlightMode.HOLD:
                await self._action.hold()
            elif mode is FlightMode.RTL:
                await self._action.return_to_launch()
            else:
                await self._action.land()
        except Exception as exc:
            return await self._refused(mode.value, exc, since)
        return accepted(mode.value)

    async def _start_offboard(self) -> None:
        assert self._offboard is not None
        assert self._offboard_sync is not None
        # offboard.start() refuses without a setpoint set first: hold still until the
        # mission's first one.
        self._offboard_sync.set_velocity_ned(VelocityNedYaw(0.0, 0.0, 0.0, 0.0))
        await self._offboard.start()
        self._offboard_started = True

    async def begin_setpoints(self) -> None:
        self._airborne = True
        if self._ardupilot() and not self._offboard_started:
            try:
                await self._start_offboard()
            except Exception as exc:
                log.warning("MAVSDK offboard start: %s", exc)

    async def arm(self) -> CommandResult:
        if self._action is None:
            raise LinkError("arm before the vehicle was discovered")
        since = time.monotonic()
        try:
            await self._action.arm()
        except Exception as exc:
            return await self._refused("arm", exc, since)
        return accepted("arm")

    async def _refused(self, what: str, exc: Exception, since: float) -> CommandResult:
        """An action error as a typed outcome, with the vehicle's STATUSTEXT reason."""
        result = getattr(exc, "result", None)
        name = getattr(getattr(result, "result", result), "name", "") or str(exc)
        outcome = timed_out(what, str(exc)) if "TIMEOUT" in name.upper() else denied(what, "")
        outcome = await self._with_reason(outcome, since)
        if not outcome.reason:
            outcome = denied(what, str(exc))
        log.warning("MAVSDK %s", outcome.describe())
        return outcome

    async def takeoff(self, altitude: float) -> CommandResult:
        if self.autopilot is None:
            raise LinkError("takeoff before the first HEARTBEAT")
        # COMMAND_LONG through MavlinkDirect: MAVSDK's takeoff() for ArduPilot climbs to its
        # own default altitude (2.5 m) whatever set_takeoff_altitude() said.
        return await self.command_long(
            mavlink2.MAV_CMD_NAV_TAKEOFF, *self.autopilot.takeoff_params(altitude)
        )

    async def command_long(self, command: int, *params: float) -> CommandResult:
        entry = mavlink2.enums["MAV_CMD"].get(command)
        name = entry.name if entry is not None else f"command {command}"
        direct = self._direct
        if direct is None:
            raise LinkError(f"{name} before the vehicle was discovered")
        full = list(params) + [0.0] * (7 - len(params))
        fields = {
            "target_system": self.target_system,
            "target_component": 1,
            "command": command,
            "confirmation": 0,
            **{f"param{i + 1}": v for i, v in enumerate(full)},
        }
        msg = MavlinkMessage(
            "COMMAND_LONG",
            *self._ids,
            self.target_system,
            1,
            json.dumps(fields).replace("NaN", "null"),
        )
        since = time.monotonic()
        try:
            ack = await asyncio.get_running_loop().run_in_executor(None, direct.send_command, msg)
            code = json.loads(ack.fields_json).get("result")
        except Exception as exc:  # MavlinkDirectError on a time-out
            log.warning("%s: %s", name, exc)
            return timed_out(name, str(exc))
        if code == mavlink2.MAV_RESULT_ACCEPTED:
            return accepted(name)
        label = mavlink2.enums["MAV_RESULT"].get(code)
        outcome = await self._with_reason(denied(name, "", code), since)
        if not outcome.reason:
            outcome = denied(name, label.name if label is not None else str(code), code)
        log.warning("%s", outcome.describe())
        return outcome

    def request_data_stream(self, stream_id: int, rate_hz: int) -> None:
        if self._direct is None:
            return
        fields = {
            "target_system": self.target_system,
            "target_component": 1,
            "req_stream_id": stream_id,
            "req_message_rate": rate_hz,
            "start_stop": 1,
        }
        msg = MavlinkMessage(
            "REQUEST_DATA_STREAM", *self._ids, self.target_system, 1, json.dumps(fields)
        )
        try:
            self._direct.send_message(msg)
        except Exception as exc:
            log.warning("REQUEST_DATA_STREAM not sent: %s", exc)

    async def read_param(self, name: str) -> float | None:
        if self._param is None:
            return None
        for getter in (self._param.get_param_float, self._param.get_param_int):
            try:
                return float(await getter(name))
            except Exception as exc:  # ParamError: absent, wrong type or a time-out
                log.debug("MAVSDK %s: %s", name, exc)
        return None

    async def set_param(self, name: str, value: float, param_type: int) -> float | None:
        if self._param is None:
            return None
        param = self._param

        async def as_int() -> None:
            await param.set_param_int(name, round(value))

        async def as_float() -> None:
            await param.set_param_float(name, value)

        setters = [as_int, as_float]
        # The plugin checks the type against what the autopilot reported (ArduPilot: INT8,
        # INT16...): the other setter where the first is refused as of another type.
        if param_type not in _INTEGER_TYPES:
            setters.reverse()
        for k, setter in enumerate(setters):
            try:
                await setter()
                break
            except Exception as exc:
                if k == len(setters) - 1:
                    log.warning("MAVSDK %s=%g: %s", name, value, exc)
                    return None
        return await self.read_param(name)

    async def download_log(self, stem: Path, limit: float) -> FlightLog:
        if self._system is None:
            return FlightLog(None, note="the MAVSDK link is closed")
        return await download_newest(self._system, stem, limit)

    async def _set_sensor(self, index: int) -> CommandResult:
        if self._param is None:
            return timed_out("MDM_SENSOR", "vehicle not discovered")
        try:
            await self._param.set_param_int("MDM_SENSOR", index)
        except Exception as exc:
            log.warning("MAVSDK MDM_SENSOR=%d: %s", index, exc)
            return timed_out("MDM_SENSOR", str(exc))
        return accepted("MDM_SENSOR")


def _repack(name: str, fields: dict[str, Any], system: int) -> bytes:
    """Re-encode a MavlinkDirect message for the .tlog (b'' when it cannot be)."""
    from pymavlink.dialects.v20 import ardupilotmega as mavlink2

    cls = getattr(mavlink2, f"MAVLink_{name.lower()}_message", None)
    if cls is None:
        return b""
    try:
        args = []
        for field in cls.fieldnames:
            value = fields[field]
            args.append(value.encode() if isinstance(value, str) else value)
        mav = mavlink2.MAVLink(None, srcSystem=system, srcComponent=1)
        return bytes(cls(*args).pack(mav))
    except (KeyError, TypeError, ValueError, AttributeError, Exception):
        return b""


def _number(value: Any) -> float:
    """A float field of MAVSDK's JSON: NaN and the infinities may come as null or as text."""
    if value is None:
        return math.nan
    return float(value)
