"""A seeded corpus of well-formed MAVLink messages with hostile contents, and reproductions of
hostile sequences once reported against the emulator: what a vehicle must survive without crashing, hanging, producing NaN, jumping, or
shutting out other clients. Each item is one packed frame (one datagram)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from sim_vehicle_stub.mavlink import dialect as d

_NASTY = (math.nan, math.inf, -math.inf, 1e38, -1e38, 1e9, -1e9, 0.0, -1.0, 21196.0, 3.4e38)
_COMMANDS = (400, 176, 22, 21, 20, 178, 192, 511, 512, 410, 520, 31999, 246, 183, 300, 224,
             207, 179, 115, 17)  # fmt: skip
_PARAMS = (b"MDM_SENSOR", b"MDM_SENS_R0", b"MDM_TAU", b"MPC_XY_VEL_MAX", b"WPNAV_SPEED",
           b"COM_OF_LOSS_T", b"GUID_TIMEOUT", b"MIS_TAKEOFF_ALT", b"NO_SUCH_PARAM", b"")  # fmt: skip
_MODES = (0, 2, 4, 5, 6, 9, 17, 0x10000, 0x30000, 0x60000, 0x2040000, 0x3040000, 0x5040000,
          0x6040000, 0xFFFFFFFF, 0x70000)  # fmt: skip


def _value(rng: np.random.Generator) -> float:
    if rng.random() < 0.6:
        return float(_NASTY[int(rng.integers(len(_NASTY)))])
    return float(rng.normal(0.0, 10.0 ** float(rng.integers(0, 8))))


def _f32(x: float) -> float:
    """A float that packs into a float field (1e39 would not): inf keeps its sign."""
    if math.isnan(x) or abs(x) <= 3.4e38:
        return x
    return math.copysign(math.inf, x)


def _int32(x: float) -> int:
    return int(max(-(2**31), min(2**31 - 1, x))) if math.isfinite(x) else 0


def _command(rng: np.random.Generator, target: int) -> Any:
    cmd = _COMMANDS[int(rng.integers(len(_COMMANDS)))]
    p = [_f32(_value(rng)) for _ in range(7)]
    if rng.random() < 0.5:
        return d.MAVLink_command_long_message(target, 1, cmd, 0, *p)
    frame = int(rng.integers(0, 12))
    return d.MAVLink_command_int_message(
        target, 1, frame, cmd, 0, 0, *p[:4], _int32(p[4] * 1e7), _int32(p[5] * 1e7), p[6]
    )


def _local_target(rng: np.random.Generator, target: int) -> Any:
    v = [_f32(_value(rng)) for _ in range(11)]
    frame = int((1, 7, 8, 9, 0, 42)[int(rng.integers(6))])
    mask = int(rng.integers(0, 4096))
    return d.MAVLink_set_position_target_local_ned_message(0, target, 1, frame, mask, *v)


def _global_target(rng: np.random.Generator, target: int) -> Any:
    v = [_f32(_value(rng)) for _ in range(9)]
    frame = int((0, 3, 5, 6, 10, 11, 2)[int(rng.integers(7))])
    lat, lon = (int(rng.integers(-(2**31), 2**31 - 1)) for _ in range(2))
    mask = int(rng.integers(0, 4096))
    return d.MAVLink_set_position_target_global_int_message(0, target, 1, frame, mask, lat, lon, *v)


def _param_set(rng: np.random.Generator, target: int) -> Any:
    name = _PARAMS[int(rng.integers(len(_PARAMS)))]
    return d.MAVLink_param_set_message(target, 1, name, _f32(_value(rng)), int(rng.integers(0, 12)))


def _set_mode(rng: np.random.Generator, target: int) -> Any:
    mode = _MODES[int(rng.integers(len(_MODES)))]
    return d.MAVLink_set_mode_message(target, int(rng.integers(0, 256)), mode)


def _mission(rng: np.random.Generator, target: int) -> Any:
    if rng.random() < 0.5:
        return d.MAVLink_mission_count_message(
            target, 1, int(rng.integers(0, 65536)), int(rng.integers(0, 256))
        )
    return d.MAVLink_mission_clear_all_message(target, 1, int(rng.integers(0, 256)))


def _plan_item(rng: np.random.Generator, target: int) -> Any:
    """An item of an upload (INT or legacy float), a partial list or a request, any plan."""
    k = int(rng.integers(4))
    seq, kind = int(rng.integers(0, 8)), int(rng.integers(0, 3))
    cmd = int(rng.choice((16, 17, 19, 20, 21, 22, 177, 178, 5001, 5003, 5100, 31999)))
    p = [_f32(_value(rng)) for _ in range(4)]
    frame = int(rng.choice((0, 2, 3, 6, 12)))
    if k == 0:
        x, y = _int32(_value(rng)), _int32(_value(rng))
        return d.MAVLink_mission_item_int_message(
            target, 1, seq, frame, cmd, 0, 1, *p, x, y, _f32(_value(rng)), kind
        )
    if k == 1:
        xy = (_f32(_value(rng)), _f32(_value(rng)))
        return d.MAVLink_mission_item_message(
            target, 1, seq, frame, cmd, 0, 1, *p, *xy, _f32(_value(rng)), kind
        )
    if k == 2:
        start, end = (int(rng.integers(-2, 10)) for _ in range(2))
        return d.MAVLink_mission_write_partial_list_message(target, 1, start, end, kind)
    return d.MAVLink_mission_request_message(target, 1, seq, kind)


def _pilot(rng: np.random.Generator, target: int) -> Any:
    """Sticks (MANUAL_CONTROL, RC_CHANNELS_OVERRIDE) or REQUEST_DATA_STREAM, any value."""
    k = int(rng.integers(3))
    if k == 0:
        axes = (int(rng.integers(-32768, 32768)) for _ in range(4))
        return d.MAVLink_manual_control_message(target, *axes, 0)
    if k == 1:
        chans = [int(rng.integers(0, 65536)) for _ in range(8)]
        return d.MAVLink_rc_channels_override_message(target, 1, *chans)
    return d.MAVLink_request_data_stream_message(
        target, 1, int(rng.integers(0, 256)), int(rng.integers(0, 65536)), int(rng.integers(0, 2))
    )


def _other(rng: np.random.Generator, target: int) -> Any:
    k = int(rng.integers(4))
    if k == 0:
        return d.MAVLink_heartbeat_message(
            int(rng.integers(0, 40)), int(rng.integers(0, 20)), int(rng.integers(0, 256)), 0, 0, 3
        )
    if k == 1:
        q = [_f32(_value(rng)) for _ in range(4)]
        return d.MAVLink_set_attitude_target_message(
            0, target, 1, int(rng.integers(0, 256)), q, *(_f32(_value(rng)) for _ in range(4))
        )
    if k == 2:
        return d.MAVLink_timesync_message(int(rng.integers(-(2**62), 2**62)), 0)
    return d.MAVLink_param_request_read_message(target, 1, b"", int(rng.integers(-1, 32768)))


_MAKERS: tuple[Callable[[np.random.Generator, int], Any], ...] = (
    _command, _command, _command, _local_target, _local_target, _global_target, _param_set,
    _set_mode, _mission, _plan_item, _pilot, _other,
)  # fmt: skip


def reproductions(target: int) -> list[Any]:
    """The reported hostile sequences, as messages to vehicle ``target``."""
    nan = math.nan
    climb = d.MAVLink_set_position_target_local_ned_message(
        0, target, 1, 1, 3527, 0, 0, 0, 0, 0, -5.0, 0, 0, 0, 0, 0
    )
    fast = d.MAVLink_set_position_target_local_ned_message(
        0, target, 1, 1, 3527, 0, 0, 0, 9e6, 9e6, -2.0, 0, 0, 0, 0, 0
    )
    arm = d.MAVLink_command_long_message(target, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0)
    return [
        # OFFBOARD (PX4) / GUIDED (ArduPilot) before arming, then armed and disarmed in the air
        climb,
        d.MAVLink_command_long_message(target, 1, 176, 0, 1, 6, 0, 0, 0, 0, 0),
        d.MAVLink_command_long_message(target, 1, 176, 0, 1, 4, 0, 0, 0, 0, 0),
        climb,
        arm,
        climb,
        d.MAVLink_command_long_message(target, 1, 400, 0, 0, 21196, 0, 0, 0, 0, 0),
        # a speed limit of 1e38 and a velocity setpoint of 9000 km/s
        d.MAVLink_command_long_message(target, 1, 178, 0, 1, 1e38, -1, 0, 0, 0, 0),
        arm,
        fast,
        d.MAVLink_command_long_message(target, 1, 22, 0, 0, 0, 0, 0, 0, 0, 1e9),
        d.MAVLink_command_long_message(target, 1, 22, 0, *[nan] * 7),
        d.MAVLink_command_long_message(target, 1, 511, 0, 0, -1, 0, 0, 0, 0, 0),  # no heartbeat
        d.MAVLink_mission_count_message(target, 1, 5, 0),
        d.MAVLink_mission_clear_all_message(target, 1, 0),
        d.MAVLink_command_int_message(
            target, 1, 6, 192, 0, 0, -1, 1, 0, nan, int(47.4e7), int(8.55e7), 1e9
        ),
    ]


def fly_fast_frames(target: int) -> list[bytes]:
    """Frames that get a vehicle of either persona flying as fast as it may (GUIDED or
    OFFBOARD, armed, a climbing 9000 km/s velocity setpoint), so the speed limit is tested."""
    mav = d.MAVLink(None, srcSystem=77, srcComponent=190)
    fast = d.MAVLink_set_position_target_local_ned_message(
        0, target, 1, 1, 3527, 0, 0, 0, 9e6, 9e6, -2.0, 0, 0, 0, 0, 0
    )
    msgs = [
        fast,
        d.MAVLink_command_long_message(target, 1, 176, 0, 1, 6, 0, 0, 0, 0, 0),
        d.MAVLink_command_long_message(target, 1, 176, 0, 1, 4, 0, 0, 0, 0, 0),
        d.MAVLink_command_long_message(target, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0),
        d.MAVLink_command_long_message(target, 1, 178, 0, 1, 1e38, -1, 0, 0, 0, 0),
        fast,
    ]
    return [bytes(m.pack(mav)) for m in msgs]


def hostile_frames(n: int, seed: int, target: int, every: int = 500) -> list[bytes]:
    """``n`` packed frames from random senders: every ``every`` frames the reproductions
    (which also get the vehicle flying), then random hostile messages of every kind the
    vehicle handles."""
    rng = np.random.default_rng(seed)
    out = []
    msgs: list[Any] = []
    while len(msgs) < n:
        if len(msgs) % every == 0:
            msgs += reproductions(target)
        msgs.append(_MAKERS[int(rng.integers(len(_MAKERS)))](rng, target))
    for msg in msgs[:n]:
        mav = d.MAVLink(None, srcSystem=int(rng.integers(1, 256)), srcComponent=190)
        out.append(bytes(msg.pack(mav)))
    return out
