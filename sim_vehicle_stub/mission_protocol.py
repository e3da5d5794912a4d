"""The MAVLink mission protocol of one vehicle (mission, fence and rally plans): uploads, partial
uploads, downloads, clears, with the answers and result codes of the persona's autopilot
(``personas/mission_rules.py``; measured on ArduCopter and PX4 SITL, docs/protocol.md)."""

from __future__ import annotations

import math
from typing import Any

from sim_vehicle_stub.mavlink import dialect as d
from sim_vehicle_stub.mission_store import FENCE, MISSION, PLAN_TYPES, RALLY, MissionItem, Upload
from sim_vehicle_stub.node import VehicleNode
from sim_vehicle_stub.personas.mission_rules import (
    DO_COMMANDS,
    FENCE_COMMANDS,
    GLOBAL_FRAMES,
    LOCATION_COMMANDS,
    MISSION_FRAME,
    NAV_COMMANDS,
    NO_ANSWER,
    POSITION_COMMANDS,
    RALLY_COMMANDS,
    YAW_MAY_BE_NAN,
)

ACCEPTED: int = d.MAV_MISSION_ACCEPTED
UNSUPPORTED_FRAME: int = d.MAV_MISSION_UNSUPPORTED_FRAME
UNSUPPORTED: int = d.MAV_MISSION_UNSUPPORTED
NO_SPACE: int = d.MAV_MISSION_NO_SPACE
INVALID_SEQUENCE: int = d.MAV_MISSION_INVALID_SEQUENCE
INVALID_X: int = d.MAV_MISSION_INVALID_PARAM5_X
INVALID_PARAM1: int = d.MAV_MISSION_INVALID_PARAM1
INVALID_Z: int = d.MAV_MISSION_INVALID_PARAM7
ALT_MAX_M = 83_000.0
"""ArduPilot's LOCATION_ALT_MAX_M: a mission item's altitude must be below it."""
_FRAMES = GLOBAL_FRAMES | {MISSION_FRAME}
_COMMANDS = {MISSION: NAV_COMMANDS | DO_COMMANDS, FENCE: FENCE_COMMANDS, RALLY: RALLY_COMMANDS}


def _peer(msg: Any) -> tuple[int, int]:
    return msg.get_srcSystem(), msg.get_srcComponent()


def _kind(msg: Any) -> int | None:
    kind = int(getattr(msg, "mission_type", MISSION))
    return kind if kind in PLAN_TYPES else None


class MissionProtocol:
    """Answers the mission messages for any vehicle (its plans live on the vehicle)."""

    def __init__(self, home_geo: Any) -> None:
        self.home_geo = home_geo
        """Callable (vehicle) -> (lat, lon, alt AMSL) of its home: ArduPilot's item 0."""

    # ----- replies
    def _ack(self, node: VehicleNode, peer: tuple[int, int], result: int, kind: int) -> None:
        if result != ACCEPTED:
            node.stats.nacks += 1
        node.send([d.MAVLink_mission_ack_message(*peer, result, kind)])

    def _ask(self, node: VehicleNode, peer: tuple[int, int], seq: int, kind: int) -> None:
        plans = node.vehicle.plans
        legacy = node.vehicle.persona.mission.legacy_requests_only or plans.legacy_requests
        cls = d.MAVLink_mission_request_message if legacy else d.MAVLink_mission_request_int_message
        node.send([cls(*peer, seq, kind)])

    # ----- uploads
    def count(self, node: VehicleNode, msg: Any) -> None:
        """MISSION_COUNT: a full upload; 0 clears the plan."""
        kind = _kind(msg)
        if kind is None:
            return
        v, peer = node.vehicle, _peer(msg)
        store = v.plans[kind]
        n = int(msg.count)
        if n == 0:
            store.replace([])
            self._ack(node, peer, ACCEPTED, kind)
            return
        if n > v.persona.mission.max_items:
            store.upload = None
            self._ack(node, peer, NO_SPACE, kind)
            return
        store.upload = Upload(0, n - 1, peer=peer)
        self._ask(node, peer, 0, kind)

    def partial(self, node: VehicleNode, msg: Any) -> None:
        """MISSION_WRITE_PARTIAL_LIST: ArduPilot replaces items start..end; PX4 ignores it."""
        kind = _kind(msg)
        v = node.vehicle
        if kind is None or not v.persona.mission.partial_lists:
            return
        store = v.plans[kind]
        start, end = int(msg.start_index), int(msg.end_index)
        if end == -1:
            end = start
        if not 0 <= start <= end < len(store.items):
            v.say(4, "Flight plan update rejected")
            return  # ArduPilot: a STATUSTEXT, no MISSION_ACK
        store.upload = Upload(start, end, peer=_peer(msg))
        self._ask(node, _peer(msg), start, kind)

    def item(self, node: VehicleNode, msg: Any, *, legacy: bool) -> None:
        """MISSION_ITEM_INT, or the float MISSION_ITEM (legacy), of an upload in progress."""
        kind = _kind(msg)
        if kind is None:
            return
        v, peer = node.vehicle, _peer(msg)
        store = v.plans[kind]
        upload = store.upload
        if upload is None:
            return  # no upload in progress: ignored, as both autopilots do
        v.plans.legacy_requests = legacy
        if int(msg.seq) != upload.next_seq:
            self._ask(node, peer, upload.next_seq, kind)  # out of order: asked again
            return
        result = self._check(v.persona.mission, kind, msg)
        item = _to_item(msg, legacy) if result == ACCEPTED else None
        if item is None:
            store.upload = None
            self._ack(node, peer, INVALID_X if result == ACCEPTED else result, kind)
            return
        upload.items.append(item)
        if not upload.done:
            self._ask(node, peer, upload.next_seq, kind)
            return
        store.finish(upload)
        self._ack(node, peer, ACCEPTED, kind)
        if kind == MISSION:
            v.mission_run.plan_changed()

    @staticmethod
    def _check(rules: Any, kind: int, msg: Any) -> int:
        frame, command = int(msg.frame), int(msg.command)
        numbers = kind == MISSION and rules.checks_item_numbers
        if numbers and (refused := _odd_param(msg)) is not None:
            return refused
        if frame not in _FRAMES:
            return UNSUPPORTED_FRAME
        if command not in _COMMANDS[kind]:
            if kind == FENCE and rules.fence_takes_any_command:
                return ACCEPTED
            return UNSUPPORTED
        if (
            kind == MISSION
            and rules.global_frame_nav_only
            and frame in GLOBAL_FRAMES
            and command not in POSITION_COMMANDS
        ):
            return UNSUPPORTED
        z = float(msg.z)
        if numbers and command in LOCATION_COMMANDS and not abs(z) < ALT_MAX_M:
            return INVALID_Z  # NaN fails the comparison too
        return ACCEPTED

    # ----- downloads
    def request_list(self, node: VehicleNode, msg: Any) -> None:
        kind = _kind(msg)
        if kind is None:
            return
        count = len(node.vehicle.plans[kind].items)
        node.send([d.MAVLink_mission_count_message(*_peer(msg), count, kind)])

    def request(self, node: VehicleNode, msg: Any, *, legacy: bool) -> None:
        """MISSION_REQUEST_INT, or the legacy MISSION_REQUEST: the item in that form."""
        kind = _kind(msg)
        if kind is None:
            return
        v, peer, seq = node.vehicle, _peer(msg), int(msg.seq)
        store = v.plans[kind]
        if store.upload is not None and store.upload.peer == peer:
            return  # a request of our own echoed back on a shared link
        v.plans.legacy_requests = legacy  # PX4 follows the client's last message kind
        if not 0 <= seq < len(store.items):
            answer = v.persona.mission.past_end_answer
            if answer != NO_ANSWER:
                self._ack(node, peer, answer, kind)
            return
        it = store.items[seq]
        frame, x, y, z = it.frame, it.x, it.y, it.z
        rules = v.persona.mission
        if kind == MISSION and seq == 0 and rules.home_is_item0:
            lat, lon, alt = self.home_geo(v)
            frame, x, y, z = 0, round(lat * 1e7), round(lon * 1e7), alt
        current = int(kind == MISSION and seq == v.mission_run.current)
        if legacy:
            scale = 1e-7 if frame in GLOBAL_FRAMES else 1.0
            reply = d.MAVLink_mission_item_message(
                *peer, seq, frame, it.command, current, it.autocontinue, *it.params,
                x * scale, y * scale, z, kind,
            )  # fmt: skip
        else:
            reply = d.MAVLink_mission_item_int_message(
                *peer, seq, frame, it.command, current, it.autocontinue, *it.params,
                x, y, z, kind,
            )  # fmt: skip
        node.send([reply])

    def clear(self, node: VehicleNode, msg: Any) -> None:
        kind = int(getattr(msg, "mission_type", MISSION))
        v = node.vehicle
        kinds = PLAN_TYPES if kind == d.MAV_MISSION_TYPE_ALL else (kind,)
        if not set(kinds) <= set(PLAN_TYPES):
            return
        if kind == d.MAV_MISSION_TYPE_ALL and not v.persona.mission.clears_all_types:
            self._ack(node, _peer(msg), UNSUPPORTED, kind)
            return
        for k in kinds:
            v.plans[k].replace([])
        if MISSION in kinds:
            v.mission_run.plan_changed()
        self._ack(node, _peer(msg), ACCEPTED, kind)

    def ack(self, node: VehicleNode, msg: Any) -> None:
        """A client's MISSION_ACK during an upload: UNSUPPORTED is a client that takes only
        MISSION_REQUEST_INT (MAVSDK's answer to the legacy request): asked again that way
        (PX4; ArduPilot's legacy requests are what MAVSDK expects of it)."""
        kind = _kind(msg)
        if kind is None:
            return
        v, peer = node.vehicle, _peer(msg)
        upload = v.plans[kind].upload
        if upload is None or upload.peer != peer or v.persona.mission.legacy_requests_only:
            return
        if int(msg.type) == UNSUPPORTED and v.plans.legacy_requests:
            v.plans.legacy_requests = False
            self._ask(node, peer, upload.next_seq, kind)
        elif int(msg.type) != ACCEPTED:
            v.plans[kind].upload = None  # the client gave up (OPERATION_CANCELLED, errors)

    def set_current(self, node: VehicleNode, msg: Any) -> None:
        """MISSION_SET_CURRENT (deprecated for DO_SET_MISSION_CURRENT): answered with
        MISSION_CURRENT at the next stream tick."""
        node.vehicle.mission_run.set_current(int(msg.seq))


def _odd_param(msg: Any) -> int | None:
    """ArduPilot's refusal of an infinite param1-4, or a NaN one (but a NaN yaw where taken):
    INVALID_PARAM1..4 for the first such; None where all are numbers."""
    params = (msg.param1, msg.param2, msg.param3, msg.param4)
    for n, value in enumerate(float(p) for p in params):
        yaw_nan = n == 3 and int(msg.command) in YAW_MAY_BE_NAN and math.isnan(value)
        if not math.isfinite(value) and not yaw_nan:
            return INVALID_PARAM1 + n
    return None


def _to_item(msg: Any, legacy: bool) -> MissionItem | None:
    """The stored form of an item message (None: a value no field can hold)."""
    params = (float(msg.param1), float(msg.param2), float(msg.param3), float(msg.param4))
    frame = int(msg.frame)
    if legacy:
        scale = 1e7 if frame in GLOBAL_FRAMES else 1.0
        fx, fy = float(msg.x) * scale, float(msg.y) * scale
        if not (math.isfinite(fx) and math.isfinite(fy)) or max(abs(fx), abs(fy)) >= 2**31:
            return None
        x, y = round(fx), round(fy)
    else:
        x, y = int(msg.x), int(msg.y)
    if frame in GLOBAL_FRAMES and not (abs(x) <= 900_000_000 and abs(y) <= 1_800_000_000):
        return None
    return MissionItem(int(msg.command), frame, params, x, y, float(msg.z), int(msg.autocontinue))
