"""What each message the pymavlink link receives means: a pymavlink message, or a frame the fast
path unpacked (fast_frames.py), turned into one :mod:`companion.link.messages` event, or noted
(the origin, home, the vehicle's words), or handed to whoever waits for it (command and
parameter answers, the mission protocol)."""

from __future__ import annotations

import logging
from abc import abstractmethod
from typing import Any, cast

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.autopilots import UnknownAutopilotError, autopilot_for
from companion.link import fast_frames
from companion.link.base import VehicleLink
from companion.link.fence_protocol import MISSION_KINDS
from companion.link.log_transfer import LOG_KINDS
from companion.link.messages import (
    Heartbeat,
    LinkEvent,
    SensorContact,
    SensorSignal,
    StatusText,
    SystemStatus,
)

log = logging.getLogger(__name__)

_NOT_AUTOPILOT_TYPES = {
    mavlink2.MAV_TYPE_GCS,
    mavlink2.MAV_TYPE_ONBOARD_CONTROLLER,
    mavlink2.MAV_TYPE_GIMBAL,
    mavlink2.MAV_TYPE_ADSB,
}
_HEALTH_BITS = mavlink2.MAV_SYS_STATUS_SENSOR_GPS | mavlink2.MAV_SYS_STATUS_PREARM_CHECK
REPLY_KINDS = MISSION_KINDS | LOG_KINDS | {"COMMAND_ACK", "PARAM_VALUE"}
"""Answers to what the link asked: to :meth:`MavlinkDecoding._reply`, never events."""


class MavlinkDecoding(VehicleLink):
    """The pymavlink link's reading of messages into events. Keeps what a message tells the
    link itself: the autopilot and whether it is armed (HEARTBEAT), the vehicle's clock of the
    latest position taken (``_time_ms``, stamped on setpoints)."""

    def __init__(self) -> None:
        super().__init__()
        self._time_ms = 0
        self._armed = False

    @abstractmethod
    def _reply(self, kind: str, msg: Any) -> None:
        """A message of :data:`REPLY_KINDS`, to the command, parameter, fence or log transfer
        waiting for it."""

    def _event(self, msg_id: int, frame: bytes, received: float) -> LinkEvent | None:
        """:meth:`_fast_event`; a message no event can carry is logged and dropped."""
        try:
            return self._fast_event(msg_id, frame, received)
        except (UnknownAutopilotError, ValueError) as exc:
            self.guard.unreadable(mavlink2.mavlink_map[msg_id].msgname, exc)
            return None

    def _fast_event(self, msg_id: int, frame: bytes, received: float) -> LinkEvent | None:
        """:meth:`_translate` of a fast_frames message."""
        f = fast_frames.unpack(msg_id, frame)
        if msg_id == fast_frames.LOCAL_POSITION_NED:
            t, x, y, z, vx, vy, vz = cast(tuple[int, float, float, float, float, float, float], f)
            self.streams.note("LOCAL_POSITION_NED", t / 1000.0)
            local = self._local(frame[6], t / 1000.0, x, y, z, vx, vy, vz, received)
            if local is not None:
                self._time_ms = t
            return local
        if msg_id == fast_frames.NAMED_VALUE_FLOAT:
            t, value, raw = cast(tuple[int, float, bytes], f)
            if text_field(raw) != "SENS_SIG" or not self.guard.reading(t, value):
                return None
            return SensorSignal(t / 1000.0, value)
        if msg_id == fast_frames.DEBUG_VECT:
            usec, x, y, z, raw = cast(tuple[int, float, float, float, bytes], f)
            name = text_field(raw)
            if name not in ("DET", "CNF") or not self.guard.reading(usec, x, y, z):
                return None
            return SensorContact(name, usec / 1e6, *self._profile_xy(x, y), z)
        if msg_id == fast_frames.HEARTBEAT:
            custom, kind, autopilot, base, status, _ = cast(tuple[int, ...], f)
            return self._heartbeat(frame[6], kind, autopilot, base, custom, status)
        present, _, health, *_, battery, _, _, _ = cast(tuple[int, ...], f)  # SYS_STATUS
        return self._sys_status(present, health, battery)

    def _heartbeat(
        self,
        component: int,
        kind: int,
        autopilot: int,
        base_mode: int,
        custom_mode: int,
        system_status: int,
    ) -> Heartbeat | None:
        if component != 1 or kind in _NOT_AUTOPILOT_TYPES:
            return None
        if self.autopilot is None or self.autopilot.mav_autopilot != autopilot:
            self.autopilot = autopilot_for(autopilot)
            log.info("system %d is %s", self.target_system, self.autopilot.name)
        self._armed = bool(base_mode & 128)
        return Heartbeat(autopilot, custom_mode, self._armed, system_status)

    def _sys_status(self, present: int, health: int, battery_remaining: int) -> SystemStatus:
        self.streams.note("SYS_STATUS")
        need = present & _HEALTH_BITS
        return SystemStatus(battery_remaining, (health & need) == need)

    def _translate(self, msg: Any, received: float) -> LinkEvent | None:
        """The event of a pymavlink message of the target system, or None.

        Raises:
            UnknownAutopilotError, ValueError: the message holds what no event can carry.
        """
        kind = msg.get_type()
        if kind == "LOCAL_POSITION_NED":
            self.streams.note(kind, msg.time_boot_ms / 1000.0)
            local = self._local(
                msg.get_srcComponent(),
                msg.time_boot_ms / 1000.0,
                msg.x,
                msg.y,
                msg.z,
                msg.vx,
                msg.vy,
                msg.vz,
                received,
            )
            if local is not None:
                self._time_ms = msg.time_boot_ms
            return local
        if kind == "GLOBAL_POSITION_INT":
            return self._global(
                msg.get_srcComponent(),
                msg.time_boot_ms / 1000.0,
                msg.lat * 1e-7,
                msg.lon * 1e-7,
                msg.relative_alt * 1e-3,
            )
        if kind == "GPS_GLOBAL_ORIGIN":
            self._note_origin(msg.latitude * 1e-7, msg.longitude * 1e-7, msg.altitude * 1e-3)
            return None
        if kind == "HOME_POSITION":
            self._note_home(
                msg.latitude * 1e-7, msg.longitude * 1e-7, msg.altitude * 1e-3, msg.x, msg.y
            )
            return None
        if kind in REPLY_KINDS:
            self._reply(kind, msg)
            return None
        if kind == "DEBUG_VECT":
            name = text_field(msg.name)
            if name in ("DET", "CNF") and self.guard.reading(msg.time_usec, msg.x, msg.y, msg.z):
                north, east = self._profile_xy(msg.x, msg.y)
                return SensorContact(name, msg.time_usec / 1e6, north, east, msg.z)
            return None
        if kind == "NAMED_VALUE_FLOAT":
            if text_field(msg.name) == "SENS_SIG" and self.guard.reading(
                msg.time_boot_ms, msg.value
            ):
                return SensorSignal(msg.time_boot_ms / 1000.0, msg.value)
            return None
        if kind == "HEARTBEAT":
            return self._heartbeat(
                msg.get_srcComponent(),
                msg.type,
                msg.autopilot,
                msg.base_mode,
                msg.custom_mode,
                msg.system_status,
            )
        if kind == "STATUSTEXT":
            text = text_field(msg.text)
            self._note_text(msg.severity, text)
            return StatusText(msg.severity, text)
        if kind == "SYS_STATUS":
            return self._sys_status(
                msg.onboard_control_sensors_present,
                msg.onboard_control_sensors_health,
                msg.battery_remaining,
            )
        return None


def text_field(raw: str | bytes) -> str:
    """A MAVLink char array as text, without its trailing NULs."""
    if isinstance(raw, bytes):
        raw = raw.decode("ascii", "replace")
    return raw.rstrip("\x00")
