"""What the sim loop sends, received over real UDP sockets from a seeded flat-out run of six
vehicles of both personas flying position and velocity setpoints past targets with their
sensors on, checked against independent references rather than against recorded bytes:

- every frame is exactly what pymavlink packs from its decoded content (header, trailing-zero
  cut, CRC), each vehicle numbering its frames without a gap;
- LOCAL_POSITION_NED is, to the float32 bit, a replay of the setpoints with the shared dynamics
  (``pursuit_reference`` and ``lag_step``), and GLOBAL_POSITION_INT that replay through
  pymap3d's WGS84 conversion (to its last unit);
- SENS_SIG and the DET/CNF DEBUG_VECT are the world's ``contacts`` at the replayed positions.
"""

from __future__ import annotations

import asyncio
import functools
import socket
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pymap3d

from mdm_core.dynamics import LagModel, lag_step, pursuit_reference
from mdm_core.world import contacts
from mdm_profiles import builtin_profile
from sim_vehicle_stub.config import EmulatorConfig
from sim_vehicle_stub.emulator import Emulator
from sim_vehicle_stub.mavlink import dialect
from sim_vehicle_stub.vehicle import NeuSetpoint
from tests.emulator_harness import free_udp_base

PROFILE = builtin_profile("paper-fixed-false")
N = 6
SIM_SECONDS = 40.0
VELOCITY = (12.0, -19.0)
"""Faster than the vehicles fly: the emulator scales it down to their speed."""


@dataclass
class Received:
    """Every datagram one vehicle sent, and the messages of each, decoded."""

    datagrams: list[bytes] = field(default_factory=list)
    decoded: list[list[Any]] = field(default_factory=list)

    def of_type(self, name: str) -> list[Any]:
        return [m for frames in self.decoded for m in frames if m.get_type() == name]


class Sink(asyncio.DatagramProtocol):
    def __init__(self, into: Received) -> None:
        self.into = into

    def datagram_received(self, data: bytes, addr: Any) -> None:
        self.into.datagrams.append(data)


def _sensor(i: int) -> int:
    return (i + i // 2) % 2


def _configure(emu: Emulator) -> None:
    """Vehicle i starts 700 m from target i, its sensor on (each persona with each sensor), and
    flies past the target: to a point beyond it or at a fixed velocity (each persona both),
    climbing to 20-30 m."""
    targets = emu.sensors.targets_at(0.0)
    for v in emu.vehicles:
        i = v.index
        for name in ("COM_OF_LOSS_T", "GUID_TIMEOUT"):  # no client streams setpoints
            if name in v.params:
                v.params.set(name, 1e9)
        v.params.set("MDM_SENSOR", _sensor(i))
        v.apply_params()
        beyond = (float(targets[i, 0]) + 300.0, float(targets[i, 1]) - 500.0)
        sp = NeuSetpoint(0.0, beyond, None, 20.0 + 2 * i, None, None)
        if (i // 2) % 2:
            sp = NeuSetpoint(0.0, None, VELOCITY, 20.0 + 2 * i, None, None)
        v.on_setpoint(sp)  # PX4 takes OFFBOARD only after a setpoint
        v.arm(True)
        v.set_mode(v.persona.mode(v.persona.external_mode))
        v.on_setpoint(sp)


async def _fly(cfg: EmulatorConfig) -> tuple[list[Received], Emulator]:
    loop = asyncio.get_running_loop()
    received = [Received() for _ in range(N)]
    sinks = []
    for i, into in enumerate(received):
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 22)
        sock.bind(("127.0.0.1", cfg.base_port + i))
        transport, _ = await loop.create_datagram_endpoint(functools.partial(Sink, into), sock=sock)
        sinks.append(transport)
    emu = Emulator(cfg)
    _configure(emu)
    await emu.start()
    try:
        while emu.clock.now < SIM_SECONDS and emu.running:
            await asyncio.sleep(0.01)
    finally:
        await emu.stop()
        await asyncio.sleep(0.05)  # the last datagrams in flight
        for transport in sinks:
            transport.close()
    return received, emu


def _start_positions() -> tuple[tuple[float, float], ...]:
    """700 m from targets 0..N-1, so that each vehicle's path passes within ~30 m of one."""
    probe = Emulator(EmulatorConfig(profile=PROFILE, vehicles=N, seed=3, speedup=None))
    where = probe.sensors.targets_at(0.0)
    return tuple((float(n) - 400.0, float(e) + 574.5) for n, e in where[:N])


def _check_frames(sysid: int, got: Received) -> None:
    """Each datagram is whole frames, each byte-equal to pymavlink's packing of its content."""
    parser = dialect.MAVLink(None)
    packer = dialect.MAVLink(None, srcSystem=sysid, srcComponent=1)
    seq = None
    for data in got.datagrams:
        frames = parser.parse_buffer(data) or []
        assert sum(len(m.get_msgbuf()) for m in frames) == len(data)
        for msg in frames:
            raw = bytes(msg.get_msgbuf())
            assert (msg.get_srcSystem(), msg.get_srcComponent()) == (sysid, 1)
            assert seq is None or msg.get_seq() == (seq + 1) & 0xFF, "a frame is missing"
            seq = msg.get_seq()
            packer.seq = seq
            assert bytes(msg.pack(packer)) == raw, msg
        got.decoded.append(frames)


def _replay(
    cfg: EmulatorConfig, setup: dict[str, np.ndarray], total: int
) -> tuple[dict[int, np.ndarray], np.ndarray]:
    """(north, east, up, vn, ve, vu) of every vehicle at each telemetry tick's time_boot_ms, and
    after ``total`` physics steps, from the setpoints alone."""
    model = LagModel(PROFILE.fleet.tau)
    k = 1.0 / (4.0 * model.tau)
    steps = _steps_per_tick(cfg)
    dt = 1.0 / cfg.telemetry_hz / steps
    where = np.column_stack([setup["pos"], np.zeros(N)])
    speed3 = np.zeros((N, 3))
    use_vel, speed = setup["use_vel"][:, None], setup["speed"]
    command = setup["h_vel"].copy()
    climb = setup["climb"]
    t, out = 0.0, {}
    for step in range(total):
        norm = np.hypot(command[:, 0], command[:, 1])
        command *= np.where(norm > speed, speed / np.maximum(norm, 1e-9), 1.0)[:, None]
        offset = setup["h_target"] - where[:, :2]
        cap = np.minimum(speed, k * np.hypot(offset[:, 0], offset[:, 1]))
        pursuit = pursuit_reference(where[:, :2], setup["h_target"], cap)
        if step == steps:  # the first tick set each persona's climb limit
            climb = setup["climb_limit"]
        up = np.clip(k * (setup["v_target"] - where[:, 2]), -setup["descent"], climb)
        reference = np.column_stack([np.where(use_vel, command, pursuit), up])
        where, speed3 = lag_step(where, speed3, reference, dt, model)
        t += dt
        if (step + 1) % steps == 0:
            out[int(t * 1000.0)] = np.hstack([where, speed3])
    return out, np.hstack([where, speed3])


def _steps_per_tick(cfg: EmulatorConfig) -> int:
    return max(1, round(1.0 / cfg.telemetry_hz / cfg.sim_step))


def test_flat_out_telemetry_is_pymavlink_framing_of_the_replayed_flight() -> None:
    base = free_udp_base(N)
    cfg = EmulatorConfig(
        profile=PROFILE,
        vehicles=N,
        base_port=base,
        bind_port_base=0,
        speedup=None,
        seed=3,
        personas=("px4", "ardupilot"),
        start_positions=_start_positions(),
    )
    probe = Emulator(cfg)
    _configure(probe)
    f = probe.fleet
    assert not f.v_use_vel.any()
    setup = {
        "pos": f.pos.copy(),
        "h_target": f.h_target.copy(),
        "h_vel": f.h_vel.copy(),
        "use_vel": f.h_use_vel.copy(),
        "speed": f.speed.copy(),
        "climb": f.climb.copy(),
        "descent": f.descent.copy(),
        "v_target": f.v_target.copy(),
        "climb_limit": np.array([v.climb_limit for v in probe.vehicles]),
    }
    received, emu = asyncio.run(_fly(cfg))
    assert emu.tick_errors == 0
    assert emu.telemetry_errors == 0
    steps = round(emu.clock.now * cfg.telemetry_hz * _steps_per_tick(cfg))
    state, last = _replay(cfg, setup, steps)
    # the float64 state itself, which float32 telemetry shows only in part, to the bit
    f = emu.fleet
    assert np.array_equal(np.column_stack([f.pos, f.alt, f.vel, f.vz]), last)
    assert (f.alt > 15.0).all()
    targets = emu.sensors.targets_at(0.0)
    spec = emu.scenario.targets
    radii = np.array([s.radius for s in emu.scenario.sensors])
    seen = {"DET": 0, "CNF": 0}
    for i, got in enumerate(received):
        _check_frames(i + 1, got)
        lpn = got.of_type("LOCAL_POSITION_NED")
        assert len(lpn) >= SIM_SECONDS * cfg.telemetry_hz
        # The local frame starts where the vehicle booted (its EKF origin), as on an autopilot.
        on, oe = emu.vehicles[i].origin
        for m in lpn:
            s = state[m.time_boot_ms][i]
            wire = [m.x, m.y, m.z, m.vx, m.vy, m.vz]
            expect = np.array([s[0] - on, s[1] - oe, -s[2], s[3], s[4], -s[5]], dtype=np.float32)
            assert wire == expect.tolist(), (i, m.time_boot_ms)
        geo = emu.geo
        for m in got.of_type("GLOBAL_POSITION_INT"):
            s = state[m.time_boot_ms][i]
            lat, lon, _ = pymap3d.ned2geodetic(s[0], s[1], -s[2], geo.lat, geo.lon, geo.alt)
            assert abs(m.lat - lat * 1e7) <= 1.0
            assert abs(m.lon - lon * 1e7) <= 1.0
            assert m.relative_alt == int(s[2] * 1000)
            assert m.alt == int((geo.alt + s[2]) * 1000)
            assert (m.vx, m.vy, m.vz) == (int(s[3] * 100), int(s[4] * 100), int(-s[5] * 100))
        sensor = _sensor(i)
        confirms = np.array([sensor == len(radii) - 1])
        assert len(got.of_type("NAMED_VALUE_FLOAT")) == len(lpn)
        for frames in got.decoded:
            signals = [m for m in frames if m.get_type() == "NAMED_VALUE_FLOAT"]
            if not signals:
                continue
            (m,) = signals  # one reading per tick, in the tick's datagram
            assert m.name == "SENS_SIG"
            pos = state[m.time_boot_ms][i][None, :2]
            mask, strength = contacts(
                radii[sensor : sensor + 1],
                confirms,
                pos,
                targets,
                np.ones(len(targets), bool),
                spec.false_mask,
            )
            visible = ~(confirms[0] & spec.false_mask)
            assert m.value == np.float32(strength[0][visible].max(initial=0.0))
            hits = [
                (float(targets[j, 0]) - on, float(targets[j, 1]) - oe, float(strength[0, j]))
                for j in np.flatnonzero(mask[0])
            ]
            sent = [v for v in frames if v.get_type() == "DEBUG_VECT"]
            expect_hits = np.array(hits, dtype=np.float32).reshape(-1, 3).tolist()
            assert [[v.x, v.y, v.z] for v in sent] == expect_hits
            name = "CNF" if confirms[0] else "DET"
            assert all(v.name == name for v in sent)
            seen[name] += len(sent)
    assert seen["DET"] > 0
    assert seen["CNF"] > 0
