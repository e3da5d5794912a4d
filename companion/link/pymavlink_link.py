"""The default backend: pymavlink's MAVLink 2 codec on asyncio sockets (UDP in/out, TCP)."""

from __future__ import annotations

import asyncio
import logging
import math
import time
from pathlib import Path
from typing import Any, cast

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.autopilots import FlightMode, UnknownAutopilotError, autopilot_for
from companion.guidance import NedSetpoint
from companion.link import fast_frames
from companion.link.address import Address, parse_address
from companion.link.base import LinkError, SetpointKind, VehicleLink
from companion.link.fence_protocol import MISSION_KINDS, FenceTransfer
from companion.link.mavlink_commands import PARAM_INT32, MavlinkCommands
from companion.link.mavlink_transport import MavlinkTransport
from companion.link.messages import (
    Heartbeat,
    LinkEvent,
    LocalPosition,
    SensorContact,
    SensorSignal,
    StatusText,
    StraySource,
    SystemStatus,
)
from companion.link.outcome import CommandResult, accepted, denied, timed_out
from companion.link.tlog import TelemetryLog
from mavlink_signing import SigningState, Verdict

log = logging.getLogger(__name__)

VELOCITY_MASK = 3527
"""SET_POSITION_TARGET_LOCAL_NED type_mask: vx, vy, vz only (ArduPilot and PX4 accept it)."""
POSITION_MASK = 3576
"""type_mask: x, y, z only."""
_NOT_AUTOPILOT_TYPES = {
    mavlink2.MAV_TYPE_GCS,
    mavlink2.MAV_TYPE_ONBOARD_CONTROLLER,
    mavlink2.MAV_TYPE_GIMBAL,
    mavlink2.MAV_TYPE_ADSB,
}
_HEALTH_BITS = mavlink2.MAV_SYS_STATUS_SENSOR_GPS | mavlink2.MAV_SYS_STATUS_PREARM_CHECK
_BESIDE_POSITION = frozenset(
    {fast_frames.HEARTBEAT, fast_frames.SYS_STATUS, fast_frames.DEBUG_VECT}
)
"""What ``_answer`` takes beside the position and the signal: each second's HEARTBEAT and
SYS_STATUS, the sensor's contacts."""


class PymavlinkLink(VehicleLink):
    """A vehicle over pymavlink.

    Args:
        url: ``udpin:0.0.0.0:14540`` (vehicle sends first), ``udpout:HOST:PORT`` or ``tcp:HOST:PORT``.
        target_system: the vehicle's system id; messages of other systems are ignored.
        system_id / component_id: the companion's own ids (onboard computer 191).
        tlog: path of the .tlog to append to, or None.
        command_timeout / command_tries: transport retries of COMMAND_LONG and PARAM_SET (wall s).
        signing_key: MAVLink 2 signing secret (32 bytes), or None. With a key, every message sent
            is signed, and received messages that are unsigned, wrongly signed or replayed are
            dropped and counted in ``signing_rejected``.
    """

    uploads_fence = True

    def __init__(
        self,
        *,
        url: str,
        target_system: int,
        system_id: int = 245,
        component_id: int = 191,
        tlog: Path | None = None,
        command_timeout: float = 1.0,
        command_tries: int = 5,
        signing_key: bytes | None = None,
    ) -> None:
        super().__init__()
        self.address: Address = parse_address(url)
        self.target_system = target_system
        self._mav = mavlink2.MAVLink(None, srcSystem=system_id, srcComponent=component_id)
        self._mav.robust_parsing = True
        self._tlog_path = tlog
        self._tlog: TelemetryLog | None = None
        self._net = MavlinkTransport(self.address, self._on_datagram, self._on_stream)
        """udpin: ``remote`` is the vehicle's address, locked to the first that sent the target
        system's messages (released only on reconnect, after the link was lost)."""
        self._strays: set[tuple[str, int]] = set()
        self._time_ms = 0
        self._armed = False
        self.bad_packets = 0
        self._signing = SigningState(signing_key) if signing_key is not None else None
        self.signing_rejected = 0
        self._fence = FenceTransfer(self._mav, self._send, target_system)
        self._commands = MavlinkCommands(
            self._mav,
            self._send,
            target_system,
            timeout=command_timeout,
            tries=command_tries,
            with_reason=self._with_reason,
            bytewise=self._bytewise,
        )
        self._pending: list[LinkEvent] = []
        """Events of the datagrams read in this callback, published together at its end."""

    def describe(self) -> str:
        return self.address.url()

    async def open(self) -> None:
        if self._tlog_path is not None and self._tlog is None:
            self._tlog = TelemetryLog(self._tlog_path)
        await self._net.open()
        log.info("link open on %s for system %d", self.address.url(), self.target_system)

    async def close(self) -> None:
        self._net.close()
        if self._tlog is not None:
            self._tlog.close()
            self._tlog = None

    async def reconnect(self) -> None:
        """UDP in: keep the bound port (the vehicle sends to it again); others: re-open."""
        if self.address.scheme == "udpin" and self._net.is_open:
            self._net.remote = None  # the vehicle may come back from another port (a restart)
            self._strays.clear()
            return
        await self.close()
        await asyncio.sleep(0.1)  # let the old transport release its socket
        await self.open()

    # -- receiving -------------------------------------------------------------------------

    def _on_datagram(self, data: bytes, addr: tuple[str | Any, int]) -> None:
        if self.answerer is not None and self._answer(data, addr):
            return
        self._receive(data, addr)
        self._net.drain(self._receive)
        self._publish_pending()

    def _on_stream(self, data: bytes) -> None:
        self._receive(data, None)
        self._publish_pending()

    def _answer(self, data: bytes, addr: tuple[str | Any, int]) -> bool:
        """A datagram of the locked vehicle holding one LOCAL_POSITION_NED, the sensor's signal
        (NAMED_VALUE_FLOAT), HEARTBEAT, SYS_STATUS and contacts (DEBUG_VECT) and nothing else,
        with no datagram waiting behind it: to the answerer when it says the position only
        needs steering, the other messages as events before or after it, in their order. The
        link's own bookkeeping (.tlog, stream rates, the setpoint's time_boot_ms, the
        autopilot) is :meth:`_receive`'s. False: take the events' path (nothing was changed)."""
        answerer, net = self.answerer, self._net
        if (
            answerer is None
            or net.sock is None
            or self._signing is not None
            or self._pending
            or self.alignment is not None
            or addr != net.remote
        ):
            return False
        received = time.perf_counter()
        frames = fast_frames.split(data)
        if frames is None:
            return False
        position: tuple[int, float, float, float, float, float, float] | None = None
        signal = None
        at, component, rare = 0, 0, []
        for i, (msg_id, system, frame) in enumerate(frames):
            if system != self.target_system:
                return False
            if msg_id == fast_frames.LOCAL_POSITION_NED:
                if position is not None:  # two: the batch acts on the newest
                    return False
                position = cast(
                    tuple[int, float, float, float, float, float, float],
                    fast_frames.unpack(msg_id, frame),
                )
                at, component = i, frame[6]
            elif msg_id == fast_frames.NAMED_VALUE_FLOAT:
                _, value, name = fast_frames.unpack(msg_id, frame)
                if name == b"SENS_SIG":
                    signal = cast(float, value)
                    if not math.isfinite(signal):
                        return False  # the events' path drops and counts it
            elif msg_id in _BESIDE_POSITION:
                rare.append((i, msg_id, frame))
            else:
                return False
        if position is None:
            return False
        t, x, y, z, vx, vy, vz = position
        guard = self.guard
        if not guard.plausible_local(component, t / 1000.0, x, y, z, vx, vy, vz, received):
            return False  # the events' path drops and counts it
        if not answerer.ready(t / 1000.0, x, y):
            return False
        if net.waiting() is not False:  # another datagram: the batch acts on the newest only
            return False
        if self._tlog is not None:
            for _, _, frame in frames:
                self._tlog.write(frame)
        before: list[LinkEvent] = []
        after: list[LinkEvent] = []
        for i, msg_id, frame in rare:
            if (event := self._event(msg_id, frame, received)) is not None:
                (before if i < at else after).append(event)
        guard.local(component, t / 1000.0, x, y, z, vx, vy, vz, received)  # taken: plausible
        self._time_ms = t
        self.streams.note("LOCAL_POSITION_NED", t / 1000.0)
        pos = LocalPosition(t / 1000.0, x, y, z, vx, vy, vz, received)
        answerer.answer(pos, signal, before, after)
        return True

    def _publish_pending(self) -> None:
        batch = self._pending
        if batch:
            self._pending = []
            self.publish(batch)

    def _receive(self, data: bytes, addr: tuple[str | Any, int] | None) -> None:
        received = time.perf_counter()
        frames = fast_frames.split(data) if self._signing is None and addr is not None else None
        if frames is None:
            self._accept(data, addr, received)
            return
        for msg_id, system, frame in frames:  # the same events, fewer Python steps
            if msg_id not in fast_frames.FAST:
                self._accept(frame, addr, received)
                continue
            self.heard.add(system)
            if system != self.target_system or not self._from_vehicle(addr):
                continue
            if self._tlog is not None:
                self._tlog.write(frame)
            if (event := self._event(msg_id, frame, received)) is not None:
                self._pending.append(event)

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
            if _text(raw) != "SENS_SIG" or not self.guard.reading(t, value):
                return None
            return SensorSignal(t / 1000.0, value)
        if msg_id == fast_frames.DEBUG_VECT:
            usec, x, y, z, raw = cast(tuple[int, float, float, float, bytes], f)
            name = _text(raw)
            if name not in ("DET", "CNF") or not self.guard.reading(usec, x, y, z):
                return None
            return SensorContact(name, usec / 1e6, x, y, z)
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

    def _accept(self, data: bytes, addr: tuple[str | Any, int] | None, received: float) -> None:
        try:
            messages = self._mav.parse_buffer(data)
        except Exception as exc:  # a broken packet must never take the companion down
            self.bad_packets += 1
            log.debug("unparsable packet from %s: %s", addr, exc)
            return
        for msg in messages or ():
            if msg.get_type() == "BAD_DATA":
                self.bad_packets += 1
                continue
            system = msg.get_srcSystem()
            self.heard.add(system)
            if system != self.target_system:
                continue
            if self._signing is not None and not self._authentic(self._signing, msg):
                continue
            if not self._from_vehicle(addr):
                continue
            if self._tlog is not None:
                self._tlog.write(msg.get_msgbuf())
            try:
                event = self._translate(msg, received)
            except (UnknownAutopilotError, ValueError) as exc:
                self.guard.unreadable(msg.get_type(), exc)
                continue
            if event is not None:
                self._pending.append(event)

    def _from_vehicle(self, addr: tuple[str | Any, int] | None) -> bool:
        """udpin: lock to the first address that speaks for the target system; another
        address with the same id is dropped and reported once (a second vehicle or emulator
        with a clashing id must never be taken for ours)."""
        if addr is None or self.address.scheme != "udpin":
            return True
        source = (str(addr[0]), int(addr[1]))
        remote = self._net.remote
        if remote is None:
            self._net.remote = source
            log.info("system %d locked to %s:%d", self.target_system, *source)
            return True
        if source == remote:
            return True
        if source not in self._strays:
            self._strays.add(source)
            locked = f"{remote[0]}:{remote[1]}"
            log.warning(
                "ignoring another sender of system %d at %s:%d (locked to %s)",
                self.target_system,
                *source,
                locked,
            )
            self._pending.append(StraySource(f"{source[0]}:{source[1]}", locked))
        return False

    def _authentic(self, signing: SigningState, msg: Any) -> bool:
        verdict = signing.check(msg.get_msgbuf())
        if verdict is Verdict.OK:
            return True
        self.signing_rejected += 1
        n = self.signing_rejected
        if n == 10 ** (len(str(n)) - 1):
            log.warning(
                "dropped %s from system %d: %s (%d dropped so far)",
                msg.get_type(),
                self.target_system,
                verdict.value,
                n,
            )
        return False

    def _translate(self, msg: Any, received: float) -> LinkEvent | None:
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
        if kind in MISSION_KINDS:
            self._fence.inbox.put_nowait(msg)
            return None
        if kind == "DEBUG_VECT":
            name = _text(msg.name)
            if name in ("DET", "CNF") and self.guard.reading(msg.time_usec, msg.x, msg.y, msg.z):
                return SensorContact(name, msg.time_usec / 1e6, msg.x, msg.y, msg.z)
            return None
        if kind == "NAMED_VALUE_FLOAT":
            if _text(msg.name) == "SENS_SIG" and self.guard.reading(msg.time_boot_ms, msg.value):
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
            text = _text(msg.text)
            self._note_text(msg.severity, text)
            return StatusText(msg.severity, text)
        if kind == "SYS_STATUS":
            return self._sys_status(
                msg.onboard_control_sensors_present,
                msg.onboard_control_sensors_health,
                msg.battery_remaining,
            )
        if kind == "COMMAND_ACK":
            self._commands.on_ack(msg.command, msg.result)
            return None
        if kind == "PARAM_VALUE":
            self._commands.on_param_value(_text(msg.param_id), msg.param_value, msg.param_type)
            return None
        return None

    # -- sending ---------------------------------------------------------------------------

    def _send(self, msg: Any) -> None:
        if not self._net.is_open:
            return
        buf = msg.pack(self._mav)
        if self._signing is not None:
            buf = self._signing.sign_frame(buf, msg.crc_extra)
        self._send_frame(buf)

    def _send_frame(self, buf: bytes) -> None:
        """A packed frame out with the next sequence number's turn taken, and into the .tlog."""
        if not self._net.is_open:
            return
        self._mav.seq = (self._mav.seq + 1) % 256
        if self._net.send(buf) and self._tlog is not None:
            self._tlog.write(buf)

    def send_heartbeat(self) -> None:
        self._send(
            self._mav.heartbeat_encode(
                mavlink2.MAV_TYPE_ONBOARD_CONTROLLER,
                mavlink2.MAV_AUTOPILOT_INVALID,
                0,
                0,
                mavlink2.MAV_STATE_ACTIVE,
            )
        )

    def send_setpoint(self, setpoint: NedSetpoint, kind: SetpointKind) -> None:
        mask = VELOCITY_MASK if kind == "velocity" else POSITION_MASK
        sp = setpoint
        north, east = self._vehicle_xy(sp.north, sp.east)
        if self._signing is None:  # the frame pymavlink would pack, without its objects
            mav = self._mav
            payload = fast_frames.SETPOINT.pack(
                self._time_ms,
                north,
                east,
                sp.down,
                sp.vn,
                sp.ve,
                sp.vd,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
                mask,
                self.target_system,
                1,
                mavlink2.MAV_FRAME_LOCAL_NED,
            )
            self._send_frame(
                fast_frames.frame(
                    fast_frames.SET_POSITION_TARGET_LOCAL_NED,
                    payload,
                    mav.seq,
                    mav.srcSystem,
                    mav.srcComponent,
                )
            )
            return
        self._send(
            self._mav.set_position_target_local_ned_encode(
                self._time_ms,
                self.target_system,
                1,
                mavlink2.MAV_FRAME_LOCAL_NED,
                mask,
                north,
                east,
                sp.down,
                sp.vn,
                sp.ve,
                sp.vd,
                0,
                0,
                0,
                0,
                0,
            )
        )

    async def upload_fence(self, vertices: list[tuple[int, int]]) -> None:
        await self._fence.upload(vertices)

    async def download_fence(self) -> list[tuple[int, int]]:
        return await self._fence.download()

    async def command_long(self, command: int, *params: float) -> CommandResult:
        return await self._commands.command_long(command, *params)

    def request_data_stream(self, stream_id: int, rate_hz: int) -> None:
        self._send(
            self._mav.request_data_stream_encode(self.target_system, 1, stream_id, rate_hz, 1)
        )

    async def configure_streams(self) -> None:
        """:meth:`MavlinkCommands.configure_streams`; GLOBAL_POSITION_INT kept while the fence
        watch reads it."""
        await self._commands.configure_streams(keep_global_position=self.global_position)

    async def set_mode(self, mode: FlightMode) -> CommandResult:
        if self.autopilot is None:
            raise LinkError("set_mode before the first HEARTBEAT")
        cmd = self.autopilot.mode_command(mode, armed=self._armed)
        return await self.command_long(
            mavlink2.MAV_CMD_DO_SET_MODE, cmd.base_mode, cmd.custom_main, cmd.custom_sub
        )

    async def arm(self) -> CommandResult:
        return await self.command_long(mavlink2.MAV_CMD_COMPONENT_ARM_DISARM, 1.0)

    async def takeoff(self, altitude: float) -> CommandResult:
        if self.autopilot is None:
            raise LinkError("takeoff before the first HEARTBEAT")
        return await self.command_long(
            mavlink2.MAV_CMD_NAV_TAKEOFF, *self.autopilot.takeoff_params(altitude)
        )

    async def _set_sensor(self, index: int) -> CommandResult:
        echoed = await self.set_param("MDM_SENSOR", float(index), PARAM_INT32)
        if echoed is None:
            return timed_out("MDM_SENSOR", f"no PARAM_VALUE after {self._commands.tries} tries")
        if echoed != index:
            return denied("MDM_SENSOR", f"vehicle kept {echoed:g}, asked {index}")
        return accepted("MDM_SENSOR")

    async def read_param(self, name: str) -> float | None:
        return await self._commands.read_param(name)

    async def set_param(self, name: str, value: float, param_type: int) -> float | None:
        return await self._commands.set_param(name, value, param_type)

    def _bytewise(self) -> bool:
        """PX4 carries integer parameters bytewise in the float field; ArduPilot casts them."""
        return self.autopilot is not None and self.autopilot.name == "px4"


def _text(raw: str | bytes) -> str:
    if isinstance(raw, bytes):
        raw = raw.decode("ascii", "replace")
    return raw.rstrip("\x00")
