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
import time
from pathlib import Path
from typing import Any

from mavsdk.asyncio import Configuration, Mavsdk
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.offboard import OffboardAsync
from mavsdk.asyncio.plugins.param import ParamAsync
from mavsdk.plugins.mavlink_direct import MavlinkDirect, MavlinkMessage
from mavsdk.plugins.offboard import Offboard, PositionNedYaw, VelocityNedYaw

from companion.autopilots import Autopilot, FlightMode, UnknownAutopilotError, autopilot_for
from companion.guidance import Setpoint
from companion.link.address import parse_address
from companion.link.base import LinkError, SetpointKind, VehicleLink
from companion.link.messages import (
    Heartbeat,
    LinkEvent,
    LocalPosition,
    SensorContact,
    SensorSignal,
    SystemStatus,
)
from companion.link.tlog import TelemetryLog

log = logging.getLogger(__name__)
_SUBSCRIBED = ("HEARTBEAT", "LOCAL_POSITION_NED", "SYS_STATUS", "DEBUG_VECT", "NAMED_VALUE_FLOAT")
_HEALTH_BITS = 0x20 | 0x10000000


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
        self.address = parse_address(url)
        self.target_system = target_system
        self.events = asyncio.Queue()
        self.autopilot: Autopilot | None = None
        self._ids = (system_id, component_id)
        self._tlog_path = tlog
        self._tlog: TelemetryLog | None = None
        self._discover_timeout = discover_timeout
        self._mavsdk: Mavsdk | None = None
        self._direct: MavlinkDirect | None = None
        self._offboard_sync: Offboard | None = None
        self._action: ActionAsync | None = None
        self._offboard: OffboardAsync | None = None
        self._param: ParamAsync | None = None
        self._handles: list[Any] = []
        self._loop: asyncio.AbstractEventLoop | None = None
        self._offboard_started = False

    async def open(self) -> None:
        if self._mavsdk is not None:
            return
        self._loop = asyncio.get_running_loop()
        if self._tlog_path is not None:
            self._tlog = TelemetryLog(self._tlog_path)
        cfg = Configuration.create_manual(*self._ids, False)
        self._mavsdk = Mavsdk(cfg)
        await self._mavsdk.add_any_connection(self.address.mavsdk_url())
        system = None
        while system is None:
            system = await self._mavsdk.first_autopilot(timeout_s=self._discover_timeout)
            if system is None:
                log.info(
                    "MAVSDK: waiting for system %d on %s", self.target_system, self.address.url()
                )
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
        self._mavsdk = self._direct = self._offboard_sync = None
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
        if message.system_id != self.target_system:
            return
        try:
            fields = json.loads(message.fields_json)
            event = self._translate(message.message_name, message.component_id, fields, received)
        except (ValueError, KeyError, TypeError, UnknownAutopilotError) as exc:
            log.warning("ignored %s: %s", message.message_name, exc)
            return
        if self._tlog is not None:
            self._tlog.write(_repack(message.message_name, fields, self.target_system))
        if event is not None:
            self.events.put_nowait(event)

    def _translate(
        self, name: str, component: int, f: dict[str, Any], received: float
    ) -> LinkEvent | None:
        if name == "LOCAL_POSITION_NED":
            return LocalPosition(
                f["time_boot_ms"] / 1000.0, f["x"], f["y"], f["z"], f["vx"], f["vy"], f["vz"],
                received,
            )  # fmt: skip
        if name == "DEBUG_VECT":
            label = str(f["name"]).rstrip("\x00")
            if label in ("DET", "CNF"):
                return SensorContact(label, f["time_usec"] / 1e6, f["x"], f["y"], f["z"])
            return None
        if name == "NAMED_VALUE_FLOAT":
            if str(f["name"]).rstrip("\x00") == "SENS_SIG":
                return SensorSignal(f["time_boot_ms"] / 1000.0, f["value"])
            return None
        if name == "HEARTBEAT":
            if component != 1 or f["type"] in (6, 18, 26, 27):
                return None
            if self.autopilot is None or self.autopilot.mav_autopilot != f["autopilot"]:
                self.autopilot = autopilot_for(int(f["autopilot"]))
            return Heartbeat(
                int(f["autopilot"]), int(f["custom_mode"]), bool(f["base_mode"] & 128),
                int(f["system_status"]),
            )  # fmt: skip
        if name == "SYS_STATUS":
            need = f["onboard_control_sensors_present"] & _HEALTH_BITS
            healthy = (f["onboard_control_sensors_health"] & need) == need
            return SystemStatus(int(f["battery_remaining"]), healthy)
        return None

    # -- sending ---------------------------------------------------------------------------

    def send_heartbeat(self) -> None:
        if self._direct is None:
            return
        fields = {"type": 18, "autopilot": 8, "base_mode": 0, "custom_mode": 0,
                  "system_status": 4, "mavlink_version": 3}  # fmt: skip
        msg = MavlinkMessage("HEARTBEAT", *self._ids, 0, 0, json.dumps(fields))
        try:
            self._direct.send_message(msg)
        except Exception as exc:  # MAVSDK raises its own error types; never crash the loop
            log.debug("heartbeat not sent: %s", exc)

    def send_setpoint(self, setpoint: Setpoint, kind: SetpointKind) -> None:
        off = self._offboard_sync
        if off is None:
            return
        sp = setpoint
        try:
            if kind == "velocity":
                off.set_velocity_ned(VelocityNedYaw(sp.vn, sp.ve, sp.vd, 0.0))
            else:
                off.set_position_ned(PositionNedYaw(sp.north, sp.east, sp.down, 0.0))
        except Exception as exc:
            log.debug("setpoint not sent: %s", exc)

    async def set_mode(self, mode: FlightMode) -> bool:
        if self._action is None or self._offboard is None:
            raise LinkError("set_mode before the vehicle was discovered")
        try:
            if mode is FlightMode.GUIDED:
                await self._offboard.start()
                self._offboard_started = True
            elif mode is FlightMode.HOLD:
                await self._action.hold()
            elif mode is FlightMode.RTL:
                await self._action.return_to_launch()
            else:
                await self._action.land()
        except Exception as exc:
            log.warning("MAVSDK %s refused: %s", mode.value, exc)
            return False
        return True

    async def arm(self) -> bool:
        return await self._call("arm")

    async def takeoff(self, altitude: float) -> bool:
        if self._action is None:
            raise LinkError("takeoff before the vehicle was discovered")
        if self.autopilot is None or self._direct is None:
            return await self._call("takeoff")
        # MavlinkDirect's send_command: MAVSDK's takeoff() for ArduPilot climbs to its own
        # default altitude (2.5 m) whatever set_takeoff_altitude() said.
        p = self.autopilot.takeoff_params(altitude)
        fields = {"target_system": self.target_system, "target_component": 1, "command": 22,
                  "confirmation": 0, **{f"param{i + 1}": v for i, v in enumerate(p)}}  # fmt: skip
        msg = MavlinkMessage("COMMAND_LONG", *self._ids, self.target_system, 1,
                             json.dumps(fields).replace("NaN", "null"))  # fmt: skip
        direct = self._direct
        try:
            ack = await asyncio.get_running_loop().run_in_executor(None, direct.send_command, msg)
            result = json.loads(ack.fields_json).get("result")
        except Exception as exc:
            log.warning("MAVSDK takeoff: %s", exc)
            return False
        return bool(result == 0)

    async def set_sensor(self, index: int) -> bool:
        if self._param is None:
            return False
        try:
            await self._param.set_param_int("MDM_SENSOR", index)
        except Exception as exc:
            log.warning("MAVSDK MDM_SENSOR=%d: %s", index, exc)
            return False
        return True

    async def _call(self, action: str) -> bool:
        if self._action is None:
            raise LinkError(f"{action} before the vehicle was discovered")
        try:
            await getattr(self._action, action)()
        except Exception as exc:
            log.warning("MAVSDK %s refused: %s", action, exc)
            return False
        return True


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
