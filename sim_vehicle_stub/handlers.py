"""Incoming messages to a vehicle: dispatch by message type; unknown types are ignored."""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import Any

from sim_vehicle_stub.commands import CommandHandler
from sim_vehicle_stub.geo_frame import GeoFrame
from sim_vehicle_stub.manual_control import manual_sticks, override_sticks
from sim_vehicle_stub.mavlink import dialect as d
from sim_vehicle_stub.mission_protocol import MissionProtocol
from sim_vehicle_stub.node import VehicleNode
from sim_vehicle_stub.setpoints import attitude_setpoint, global_setpoint, local_setpoint
from sim_vehicle_stub.vehicle import ACCEPTED, DENIED

_CONTROLLER_TYPES = (d.MAV_TYPE_GCS, d.MAV_TYPE_ONBOARD_CONTROLLER)
_FTP_NAK, _FTP_ERR_FAIL = 129, 1


class MessageHandler:
    """Routes decoded messages of one vehicle to the code that answers them."""

    def __init__(
        self,
        commands: CommandHandler,
        geo: GeoFrame,
        now: Callable[[], float],
        missions: MissionProtocol,
    ) -> None:
        self.commands = commands
        self.geo = geo
        self.now = now
        m = missions
        self._table: dict[str, Callable[[VehicleNode, Any], None]] = {
            "HEARTBEAT": self._heartbeat,
            "COMMAND_LONG": self._command_long,
            "COMMAND_INT": self._command_int,
            "SET_MODE": self._set_mode,
            "PARAM_REQUEST_LIST": self._param_list,
            "PARAM_REQUEST_READ": self._param_read,
            "PARAM_SET": self._param_set,
            "SET_POSITION_TARGET_LOCAL_NED": self._local_target,
            "SET_POSITION_TARGET_GLOBAL_INT": self._global_target,
            "SET_ATTITUDE_TARGET": self._attitude_target,
            "MISSION_REQUEST_LIST": m.request_list,
            "MISSION_COUNT": m.count,
            "MISSION_WRITE_PARTIAL_LIST": m.partial,
            "MISSION_ITEM_INT": functools.partial(m.item, legacy=False),
            "MISSION_ITEM": functools.partial(m.item, legacy=True),
            "MISSION_REQUEST_INT": functools.partial(m.request, legacy=False),
            "MISSION_REQUEST": functools.partial(m.request, legacy=True),
            "MISSION_CLEAR_ALL": m.clear,
            "MISSION_SET_CURRENT": m.set_current,
            "MISSION_ACK": m.ack,
            "MANUAL_CONTROL": self._manual_control,
            "RC_CHANNELS_OVERRIDE": self._rc_override,
            "REQUEST_DATA_STREAM": self._data_stream,
            "FILE_TRANSFER_PROTOCOL": self._ftp,
            "LOG_REQUEST_LIST": self._log_list,
            "TIMESYNC": self._timesync,
        }

    def handle(self, node: VehicleNode, msg: Any) -> None:
        """Answer one message; messages addressed to another system are counted and skipped."""
        target = getattr(msg, "target_system", 0)
        if target not in (0, node.vehicle.sysid):
            node.stats.not_for_us += 1
            return
        fn = self._table.get(msg.get_type())
        if fn is not None:
            fn(node, msg)

    def _heartbeat(self, node: VehicleNode, msg: Any) -> None:
        v = node.vehicle
        controller = msg.type in _CONTROLLER_TYPES or msg.autopilot == d.MAV_AUTOPILOT_INVALID
        if controller and v.persona.watches_heartbeat(v.params, msg.get_srcSystem()):
            v.last_gcs_heartbeat = self.now()

    def _command_long(self, node: VehicleNode, msg: Any) -> None:
        p = (msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6, msg.param7)
        self.commands.handle(node, msg, p)

    def _command_int(self, node: VehicleNode, msg: Any) -> None:
        p = (msg.param1, msg.param2, msg.param3, msg.param4, float(msg.x), float(msg.y), msg.z)
        self.commands.handle(node, msg, p, int(msg.frame))

    def _set_mode(self, node: VehicleNode, msg: Any) -> None:
        v = node.vehicle
        mode = v.persona.mode_by_custom(int(msg.custom_mode))
        result = DENIED if mode is None else v.set_mode(mode)
        if result != ACCEPTED:
            node.stats.nacks += 1
        node.send(
            [
                d.MAVLink_command_ack_message(
                    d.MAVLINK_MSG_ID_SET_MODE,
                    result,
                    0,
                    0,
                    msg.get_srcSystem(),
                    msg.get_srcComponent(),
                )
            ]
        )

    # ----- parameters
    def _param_value(self, node: VehicleNode, name: str) -> Any:
        table = node.vehicle.params
        return d.MAVLink_param_value_message(
            name.encode(),
            table.wire_value(name),
            int(table.spec(name).kind),
            len(table),
            table.index(name),
        )

    def _param_list(self, node: VehicleNode, msg: Any) -> None:
        node.send([self._param_value(node, n) for n in node.vehicle.params.names()])

    def _param_read(self, node: VehicleNode, msg: Any) -> None:
        table = node.vehicle.params
        name = table.name_at(msg.param_index) if msg.param_index >= 0 else msg.param_id
        if name is not None and name in table:
            node.send([self._param_value(node, name)])

    def _param_set(self, node: VehicleNode, msg: Any) -> None:
        v = node.vehicle
        name = msg.param_id
        if name not in v.params:
            node.stats.nacks += 1
            return
        try:
            v.params.set(name, v.params.decode(name, msg.param_value))
        except ValueError as exc:
            node.stats.nacks += 1
            v.say(4, f"param {exc}")
        v.apply_params()
        node.send([self._param_value(node, name)])

    # ----- setpoints
    def _local_target(self, node: VehicleNode, msg: Any) -> None:
        sp = local_setpoint(msg, node.vehicle, self.now())
        if sp is None:
            node.stats.nacks += 1
        else:
            node.vehicle.on_setpoint(sp)

    def _global_target(self, node: VehicleNode, msg: Any) -> None:
        sp = global_setpoint(msg, self.geo, self.now())
        if sp is None:
            node.stats.nacks += 1
        else:
            node.vehicle.on_setpoint(sp)

    def _attitude_target(self, node: VehicleNode, msg: Any) -> None:
        sp = attitude_setpoint(msg, node.vehicle, self.now())
        if sp is None:
            node.stats.nacks += 1
        else:
            node.vehicle.on_setpoint(sp)

    # ----- pilot, streams, FTP, time
    def _manual_control(self, node: VehicleNode, msg: Any) -> None:
        sticks = manual_sticks(msg)
        if sticks is None:
            node.stats.nacks += 1
        else:
            node.vehicle.pilot.take(sticks, self.now())

    def _rc_override(self, node: VehicleNode, msg: Any) -> None:
        sticks = override_sticks(msg)
        if sticks is not None:
            node.vehicle.pilot.take(sticks, self.now())

    def _data_stream(self, node: VehicleNode, msg: Any) -> None:
        if node.vehicle.persona.data_streams:
            node.schedule.request_data_stream(
                int(msg.req_stream_id), int(msg.req_message_rate), bool(msg.start_stop)
            )

    def _ftp(self, node: VehicleNode, msg: Any) -> None:
        req = bytes(msg.payload)
        if len(req) < 12:
            return
        seq = (int.from_bytes(req[0:2], "little") + 1) & 0xFFFF
        reply = bytearray(251)
        reply[0:2] = seq.to_bytes(2, "little")
        reply[2] = req[2]  # session
        reply[3] = _FTP_NAK
        reply[4] = 1  # size
        reply[5] = req[3]  # the opcode being refused
        reply[12] = _FTP_ERR_FAIL
        node.send(
            [
                d.MAVLink_file_transfer_protocol_message(
                    0, msg.get_srcSystem(), msg.get_srcComponent(), list(reply)
                )
            ]
        )

    def _log_list(self, node: VehicleNode, msg: Any) -> None:
        """The emulator keeps no autopilot log: one LOG_ENTRY of zeros (num_logs 0), as
        ArduPilot and PX4 answer when they hold none."""
        node.send([d.MAVLink_log_entry_message(0, 0, 0, 0, 0)])

    def _timesync(self, node: VehicleNode, msg: Any) -> None:
        if msg.tc1 == 0:
            now_ns = int(self.now() * 1e9)
            node.send([d.MAVLink_timesync_message(now_ns, msg.ts1)])


def _finite(*values: float) -> bool:
    return all(math.isfinite(x) for x in values)
