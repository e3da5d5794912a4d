"""The default backend: pymavlink's MAVLink 2 codec on asyncio sockets (UDP in/out, TCP).

This file sends: setpoints, the heartbeat, commands, parameters and the fence; what comes in
is :class:`~companion.link.mavlink_receiver.MavlinkReceiver`'s (the socket, the fast path)
and :class:`~companion.link.mavlink_decode.MavlinkDecoding`'s (messages into events)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.autopilots import FlightMode
from companion.guidance import NedSetpoint
from companion.link import fast_frames
from companion.link.base import LinkError, SetpointKind
from companion.link.fence_protocol import FenceTransfer
from companion.link.log_transfer import LOG_KINDS, FlightLog, LogTransfer
from companion.link.mavlink_commands import PARAM_INT32, MavlinkCommands
from companion.link.mavlink_decode import text_field
from companion.link.mavlink_receiver import MavlinkReceiver
from companion.link.outcome import CommandResult, accepted, denied, timed_out

VELOCITY_MASK = 3527
"""SET_POSITION_TARGET_LOCAL_NED type_mask: vx, vy, vz only (ArduPilot and PX4 accept it)."""
POSITION_MASK = 3576
"""type_mask: x, y, z only."""


class PymavlinkLink(MavlinkReceiver):
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
        super().__init__(
            url=url,
            target_system=target_system,
            system_id=system_id,
            component_id=component_id,
            tlog=tlog,
            signing_key=signing_key,
        )
        self.own_system = system_id
        self._fence = FenceTransfer(self._mav, self._send, target_system)
        self._logs = LogTransfer(self._mav, self._send, target_system)
        self._commands = MavlinkCommands(
            self._mav,
            self._send,
            target_system,
            timeout=command_timeout,
            tries=command_tries,
            with_reason=self._with_reason,
            bytewise=self._bytewise,
        )

    def _reply(self, kind: str, msg: Any) -> None:
        if kind == "COMMAND_ACK":
            self._commands.on_ack(msg.command, msg.result)
        elif kind == "PARAM_VALUE":
            self._commands.on_param_value(text_field(msg.param_id), msg.param_value, msg.param_type)
        elif kind in LOG_KINDS:
            self._logs.inbox.put_nowait(msg)
        else:
            self._fence.inbox.put_nowait(msg)

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

    async def download_log(self, stem: Path, limit: float) -> FlightLog:
        return await self._logs.download(stem, limit)

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
