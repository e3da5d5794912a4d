"""COMMAND_LONG / COMMAND_INT handling: each supported command gets a result, others UNSUPPORTED."""

from __future__ import annotations

import logging
import math
from typing import Any

from sim_vehicle_stub.flight_commands import MISSION_COMMANDS, run_flight_command
from sim_vehicle_stub.mavlink import dialect as d
from sim_vehicle_stub.node import VehicleNode
from sim_vehicle_stub.personas.ardupilot import LOCATION_ALT_MAX_M
from sim_vehicle_stub.telemetry import Telemetry
from sim_vehicle_stub.vehicle import ACCEPTED, DENIED, FAILED, UNSUPPORTED, Vehicle

_FORCE_MAGIC = 21196
_HEARTBEAT_US = (100_000, 1_000_000)
"""HEARTBEAT intervals a client may set, us (10 Hz to the default 1 Hz); 0 restores 1 Hz."""
_RELATIVE_FRAMES = (3, 6, 10, 11)
"""Global frames whose altitude is above home (terrain frames: flat terrain here)."""
log = logging.getLogger(__name__)


class CommandHandler:
    """Executes commands for any vehicle; replies go back through the node."""

    def __init__(self, telemetry: Telemetry, home_alt_amsl: float) -> None:
        self.telemetry = telemetry
        self.home_alt_amsl = home_alt_amsl

    def handle(
        self, node: VehicleNode, msg: Any, params: tuple[float, ...], frame: int | None = None
    ) -> None:
        """Run ``msg.command`` with params p1..p7 and send COMMAND_ACK to the requester;
        ``frame`` is COMMAND_INT's (p5, p6 then are degrees * 1e7), None for COMMAND_LONG."""
        extra: list[Any] = []
        try:
            result = self._run(node, int(msg.command), params, extra, frame)
        except Exception:  # a hostile parameter must not take the vehicle down
            log.exception("vehicle %d: command %s failed", node.vehicle.index, msg.command)
            result = FAILED
        if result != ACCEPTED:
            node.stats.nacks += 1
        ack = d.MAVLink_command_ack_message(
            msg.command, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent()
        )
        node.send([ack, *extra])

    def _run(
        self,
        node: VehicleNode,
        cmd: int,
        p: tuple[float, ...],
        extra: list[Any],
        frame: int | None,
    ) -> int:
        v = node.vehicle
        if cmd == d.MAV_CMD_COMPONENT_ARM_DISARM:
            return v.arm(p[0] >= 0.5, force=p[1] == _FORCE_MAGIC)
        if cmd == d.MAV_CMD_DO_SET_MODE:
            mode = v.persona.mode_from_command(p[0], p[1], p[2])
            return v.persona.unknown_mode_result if mode is None else v.set_mode(mode)
        if cmd in MISSION_COMMANDS:
            return run_flight_command(v, cmd, p, frame, self.telemetry.geo)
        if cmd == d.MAV_CMD_NAV_TAKEOFF:
            return v.takeoff(p[6], self.home_alt_amsl)
        if cmd == d.MAV_CMD_NAV_LAND:
            return v.set_mode(v.persona.mode(v.persona.land_mode))
        if cmd == d.MAV_CMD_NAV_RETURN_TO_LAUNCH:
            return v.set_mode(v.persona.mode(v.persona.rtl_mode))
        if cmd == d.MAV_CMD_DO_CHANGE_SPEED:
            return v.change_speed(p[0], p[1])
        if cmd == d.MAV_CMD_DO_REPOSITION:
            return self._reposition(v, p, frame)
        if cmd == d.MAV_CMD_SET_MESSAGE_INTERVAL:
            if not (math.isfinite(p[0]) and math.isfinite(p[1])):
                return DENIED
            msg_id = int(p[0])
            if msg_id not in self.telemetry.builders:
                return DENIED
            if msg_id in v.persona.fixed_intervals:
                return FAILED
            low, high = _HEARTBEAT_US
            if msg_id == d.MAVLINK_MSG_ID_HEARTBEAT and p[1] != 0 and not low <= p[1] <= high:
                # PX4 answers FAILED and keeps its heartbeat (measured on PX4 SITL); a vehicle
                # without one, or beating slower than 1 Hz, is lost to every client (they drop
                # a link after 3-5 s of silence), so neither persona allows it.
                return FAILED
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

    def _reposition(self, v: Vehicle, p: tuple[float, ...], frame: int | None) -> int:
        # ArduCopter handle_command_int_do_reposition: a bad position or an altitude beyond
        # LOCATION_ALT_MAX_M is DENIED; param2 bit 0 allows the mode change.
        scale = 1e-7 if frame is not None else 1.0
        lat, lon, alt = p[4] * scale, p[5] * scale, p[6]
        if not (math.isfinite(lat) and math.isfinite(lon)) or abs(lat) > 90 or abs(lon) > 180:
            return DENIED
        if math.isfinite(alt) and abs(alt) > LOCATION_ALT_MAX_M:
            return DENIED
        geo = self.telemetry.geo
        north, east, _ = geo.to_local(lat, lon, geo.alt)
        height: float | None = None
        if math.isfinite(alt):
            relative = frame in _RELATIVE_FRAMES
            height = max(alt if relative else alt - self.home_alt_amsl, 0.0)
        flags = int(p[1]) if math.isfinite(p[1]) and 0 <= p[1] < 2**31 else 0
        change_mode = bool(flags & d.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE)
        return v.reposition(north, east, height, change_mode)

    def _request(self, node: VehicleNode, msg_id: int, extra: list[Any]) -> int:
        build = self.telemetry.builders.get(msg_id)
        if build is None or msg_id in node.vehicle.persona.unrequestable:
            return DENIED
        extra.append(build(node.vehicle))
        return ACCEPTED
