"""COMMAND_LONG / COMMAND_INT handling: each supported command gets a result, others UNSUPPORTED."""

from __future__ import annotations

import logging
import math
from typing import Any

from sim_vehicle_stub.mavlink import dialect as d
from sim_vehicle_stub.node import VehicleNode
from sim_vehicle_stub.telemetry import Telemetry
from sim_vehicle_stub.vehicle import ACCEPTED, DENIED, FAILED, UNSUPPORTED

_FORCE_MAGIC = 21196
log = logging.getLogger(__name__)


class CommandHandler:
    """Executes commands for any vehicle; replies go back through the node."""

    def __init__(self, telemetry: Telemetry, home_alt_amsl: float) -> None:
        self.telemetry = telemetry
        self.home_alt_amsl = home_alt_amsl

    def handle(self, node: VehicleNode, msg: Any, params: tuple[float, ...]) -> None:
        """Run ``msg.command`` with params p1..p7 and send COMMAND_ACK to the requester."""
        extra: list[Any] = []
        try:
            result = self._run(node, int(msg.command), params, extra)
        except Exception:  # a hostile parameter must not take the vehicle down
            log.exception("vehicle %d: command %s failed", node.vehicle.index, msg.command)
            result = FAILED
        if result != ACCEPTED:
            node.stats.nacks += 1
        ack = d.MAVLink_command_ack_message(
            msg.command, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent()
        )
        node.send([ack, *extra])

    def _run(self, node: VehicleNode, cmd: int, p: tuple[float, ...], extra: list[Any]) -> int:
        v = node.vehicle
        if cmd == d.MAV_CMD_COMPONENT_ARM_DISARM:
            return v.arm(p[0] >= 0.5, force=p[1] == _FORCE_MAGIC)
        if cmd == d.MAV_CMD_DO_SET_MODE:
            mode = v.persona.mode_from_command(p[0], p[1], p[2])
            return DENIED if mode is None else v.set_mode(mode)
        if cmd == d.MAV_CMD_NAV_TAKEOFF:
            return v.takeoff(p[6], self.home_alt_amsl)
        if cmd == d.MAV_CMD_NAV_LAND:
            return v.set_mode(v.persona.mode(v.persona.land_mode))
        if cmd == d.MAV_CMD_NAV_RETURN_TO_LAUNCH:
            return v.set_mode(v.persona.mode(v.persona.rtl_mode))
        if cmd == d.MAV_CMD_DO_CHANGE_SPEED:
            if not (math.isfinite(p[1]) and p[1] > 0):
                return DENIED
            v.fleet.speed[v.index] = p[1]
            return ACCEPTED
        if cmd == d.MAV_CMD_SET_MESSAGE_INTERVAL:
            if not (math.isfinite(p[0]) and math.isfinite(p[1])):
                return DENIED
            msg_id = int(p[0])
            if msg_id not in self.telemetry.builders:
                return DENIED
            return ACCEPTED if node.schedule.set_interval(msg_id, p[1]) else DENIED
        if cmd == d.MAV_CMD_REQUEST_MESSAGE:
            if not math.isfinite(p[0]):
                return DENIED
            return self._request(node, int(p[0]), extra)
        if cmd == d.MAV_CMD_GET_HOME_POSITION:
            return self._request(node, d.MAVLINK_MSG_ID_HOME_POSITION, extra)
        if cmd == d.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES:
            return self._request(node, d.MAVLINK_MSG_ID_AUTOPILOT_VERSION, extra)
        return UNSUPPORTED

    def _request(self, node: VehicleNode, msg_id: int, extra: list[Any]) -> int:
        build = self.telemetry.builders.get(msg_id)
        if build is None:
            return DENIED
        extra.append(build(node.vehicle))
        return ACCEPTED
