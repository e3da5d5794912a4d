"""The emulator: one world, N vehicles, their endpoints and the fixed-step sim loop."""

from __future__ import annotations

import asyncio
import contextlib
import functools
import ipaddress
import logging
import socket
import struct
import time
from typing import Any

import numpy as np

from mavlink_wire import SigningState
from mdm_core.dynamics import LagModel
from mdm_core.ports import TCP_STRIDE
from mdm_core.world import Scenario
from sim_vehicle_stub.commands import CommandHandler
from sim_vehicle_stub.config import EmulatorConfig, system_id
from sim_vehicle_stub.encoder import Encoder
from sim_vehicle_stub.endpoints import GcsEndpoint, TcpServer, UdpEndpoint
from sim_vehicle_stub.events import EventLog
from sim_vehicle_stub.failsafes import check_failsafes, inside_fences
from sim_vehicle_stub.fast_streams import (
    DEBUG_VECT,
    NVF,
    POSITION_STREAMS,
    contact_payload,
    signal_payload,
)
from sim_vehicle_stub.fence_enforcement import breach
from sim_vehicle_stub.fleet_kinematics import Fleet
from sim_vehicle_stub.geo_frame import GeoFrame
from sim_vehicle_stub.handlers import MessageHandler
from sim_vehicle_stub.mavlink import dialect as d
from sim_vehicle_stub.mission_protocol import MissionProtocol
from sim_vehicle_stub.node import MISSION_CURRENT_ID, VehicleNode
from sim_vehicle_stub.personas import ProfileFacts, create_persona
from sim_vehicle_stub.personas.base import Behaviour
from sim_vehicle_stub.sensing import Reading, SensorWorld
from sim_vehicle_stub.sim_clock import SimClock
from sim_vehicle_stub.telemetry import StreamSchedule, Telemetry
from sim_vehicle_stub.vehicle import Vehicle

log = logging.getLogger(__name__)
HEARTBEAT = d.MAVLINK_MSG_ID_HEARTBEAT
_RCVBUF = 1 << 20
_MIN_SLEEP = 0.002


def _same(endpoint: UdpEndpoint) -> UdpEndpoint:
    return endpoint


def _resolve(future: asyncio.Future[None]) -> None:
    if not future.done():
        future.set_result(None)


def _udp_socket(host: str, port: int) -> socket.socket:
    """A bound, non-blocking UDP socket with a large receive buffer, so bursts wait for the
    loop instead of being lost uncounted in the kernel."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    with contextlib.suppress(OSError):
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, _RCVBUF)
    try:
        sock.bind((host, port))
    except OSError:
        sock.close()
        raise
    sock.setblocking(False)
    return sock


class Emulator:
    """Hosts every vehicle of a profile; use ``async with Emulator(cfg) as emu`` or :meth:`run`."""

    def __init__(self, config: EmulatorConfig) -> None:
        self.config = config
        profile = config.profile
        n = config.fleet_size
        self.scenario = Scenario.from_profile(profile)
        given = config.start_positions
        start, tracks = self.scenario.live_run(
            config.seed,
            n,
            profile.fleet.start,
            None if given is None else np.array(given, dtype=float).reshape(n, 2),
        )
        self.clock = SimClock(config.speedup)
        self.events = EventLog(config.events)
        self.fleet = Fleet(start, LagModel(profile.fleet.tau), profile.fleet.speed)
        o = profile.origin
        self.geo = GeoFrame(o.lat, o.lon, o.alt)
        self.sensors = SensorWorld(self.scenario, tracks, n, self.events)
        self.telemetry = Telemetry(self.fleet, self.geo, self.clock, int(time.time() * 1e6))
        scale = config.speedup if (config.scale_timeouts and config.speedup) else 1.0
        self.nodes: list[VehicleNode] = []
        for i in range(n):
            persona = create_persona(config.persona_of(i))
            facts = ProfileFacts(
                speed=profile.fleet.speed,
                tau=profile.fleet.tau,
                sensor_radii=tuple(s.radius for s in self.scenario.sensors),
                system_id=system_id(i),
                timeout_scale=max(scale, 1.0),
                battery_endurance=config.battery_endurance,
            )
            vehicle = Vehicle(
                i, persona, persona.param_table(facts), self.fleet, self.events, self._now,
                self.geo,
            )  # fmt: skip
            signing = SigningState(config.signing_key) if config.signing_key else None
            off = frozenset(() if persona.mission.current_unasked else (MISSION_CURRENT_ID,))
            self.nodes.append(
                VehicleNode(vehicle, Encoder(vehicle.sysid, signing=signing), StreamSchedule(off))
            )
        self.handler = MessageHandler(
            CommandHandler(self.telemetry, o.alt),
            self.geo,
            self._now,
            MissionProtocol(self.telemetry.home_geo),
        )
        self.udp: list[UdpEndpoint] = []
        self.tcp: list[TcpServer] = []
        self.gcs: GcsEndpoint | None = None
        self.tick_errors = 0
        self.telemetry_errors = 0
        """Messages skipped because a value did not fit its field."""
        self._task: asyncio.Task[None] | None = None
        self._stop = asyncio.Event()
        self._held: asyncio.Future[None] | None = None
        """While lockstep holds a tick: resolved by the last answer it waits for."""
        self._waiting: set[int] = set()
        """While lockstep holds a tick: the vehicles it still waits for."""
        self._silent: set[int] = set()
        """Vehicles whose client left a held tick unanswered for ``lockstep_wall`` wall s:
        lockstep does not wait for them again until their next setpoint."""
        self.lockstep_waits = 0
        """Ticks at which lockstep held sim time for a client's setpoint."""

    def _now(self) -> float:
        return self.clock.now

    @property
    def vehicles(self) -> list[Vehicle]:
        return [node.vehicle for node in self.nodes]

    # ----- lifecycle
    async def start(self) -> None:
        """Open every endpoint and start the sim loop."""
        cfg = self.config
        loop = asyncio.get_running_loop()
        if cfg.gcs:
            gcs_host = cfg.gcs_host or cfg.host
            # a socket bound to loopback cannot send beyond it
            gcs_bind = cfg.bind_host if ipaddress.ip_address(gcs_host).is_loopback else "0.0.0.0"
            _, gcs = await loop.create_datagram_endpoint(
                lambda: GcsEndpoint(self.nodes, self._deliver, (gcs_host, cfg.gcs_port)),
                local_addr=(gcs_bind, 0),
            )
            self.gcs = gcs
        for i, node in enumerate(self.nodes):
            bind = cfg.bind_port_base + i if cfg.bind_port_base else 0
            remote = (cfg.host, cfg.base_port + i)
            sock = _udp_socket(cfg.bind_host, bind)
            ep = UdpEndpoint(node, self._deliver, remote, cfg.flood_rate, sock)
            await loop.create_datagram_endpoint(functools.partial(_same, ep), sock=sock)
            self.udp.append(ep)
            node.outputs.append(ep.send)
            if self.gcs is not None:
                node.outputs.append(self.gcs.send)
            if cfg.tcp:
                server = TcpServer(node, self._deliver)
                await server.start(cfg.bind_host, cfg.tcp_base + TCP_STRIDE * i)
                self.tcp.append(server)
        self._task = asyncio.create_task(self._loop(), name="sim-loop")
        log.info(
            "emulator up: %d vehicles, speedup %s, MAVLink signing %s",
            len(self.nodes),
            cfg.speedup or "max",
            "on" if cfg.signing_key else "off",
        )

    @property
    def running(self) -> bool:
        """The simulation loop is stepping (started, and neither stopped nor crashed): what a
        test of hostile input checks after every batch."""
        return self._task is not None and not self._task.done()

    async def stop(self) -> None:
        self._stop.set()
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
        for ep in self.udp:
            if ep.transport is not None:
                ep.transport.close()
        for server in self.tcp:
            server.close()
        if self.gcs is not None and self.gcs.transport is not None:
            self.gcs.transport.close()
        self.events.close()

    async def __aenter__(self) -> Emulator:
        await self.start()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.stop()

    async def run(self, duration: float | None = None) -> None:
        """Run until ``duration`` sim seconds have passed (forever when None) or cancelled."""
        await self.start()
        self.clock.restart()
        try:
            while duration is None or self.clock.now < duration:
                if self._task is not None and self._task.done():
                    self._task.result()
                    break
                await asyncio.sleep(0.05)
        finally:
            await self.stop()

    def local_port(self, index: int) -> int:
        """The UDP port vehicle ``index`` listens on."""
        tr = self.udp[index].transport
        assert tr is not None
        return int(tr.get_extra_info("sockname")[1])

    # ----- receive path
    def _deliver(self, node: VehicleNode, msgs: list[Any]) -> None:
        before = node.vehicle.setpoint
        for msg in msgs:
            try:
                self.handler.handle(node, msg)
            except Exception:  # never let one message take the emulator down
                node.stats.malformed += 1
                log.exception("vehicle %d: error handling %s", node.vehicle.index, msg.get_type())
        v = node.vehicle
        if v.setpoint is not before:
            self._silent.discard(v.index)
        waiting, held = self._waiting, self._held
        # An answer, or anything else that ends the wait (a switch out of the external mode)
        if held is not None and v.index in waiting and not self._waits_for(v):
            waiting.discard(v.index)
            if not waiting:
                _resolve(held)  # the last answer the held tick waited for
        self._flush_state(node)

    def _flush_state(self, node: VehicleNode) -> None:
        v = node.vehicle
        out: list[Any] = []
        if node.early_heartbeat_due(self.clock.now):
            v.state_changed = False
            node.last_heartbeat = self.clock.now
            out.append(self.telemetry.heartbeat(v))
        for severity, text in v.status:
            out.append(d.MAVLink_statustext_message(severity, text.encode()))
        v.status.clear()
        out += node.take_outbox()
        node.send(out)

    # ----- sim loop
    async def _loop(self) -> None:
        cfg = self.config
        period = 1.0 / cfg.telemetry_hz
        steps = max(1, round(period / cfg.sim_step))
        dt = period / steps
        k = 0
        while not self._stop.is_set():
            self.fleet.step(dt)
            self.clock.advance(dt)
            k += 1
            if k == steps:
                k = 0
                try:
                    self._tick(period)
                except Exception:  # a bug must not stop every vehicle: log it and go on
                    self.tick_errors += 1
                    if self.tick_errors % 100 == 1:
                        log.exception(
                            "tick at t=%.2f failed (%d so far)", self.clock.now, self.tick_errors
                        )
                if cfg.lockstep:
                    await self._await_setpoints()
            wait = self.clock.wait_time()
            # epoll sleeps in whole milliseconds, so shorter waits are run ahead instead (the
            # clock is absolute, so this never drifts); the endpoints get the loop every tick.
            if wait > _MIN_SLEEP:
                await asyncio.sleep(wait)
            elif k == 0:
                await asyncio.sleep(0)

    def _unanswered(self) -> list[int]:
        """The vehicles lockstep waits for this tick (:meth:`_waits_for`)."""
        return [node.vehicle.index for node in self.nodes if self._waits_for(node.vehicle)]

    def _waits_for(self, v: Vehicle) -> bool:
        """Whether lockstep waits for ``v``: flown in the external mode by a client that is not
        silent, with no setpoint since this tick's telemetry (sim time stands still meanwhile,
        so an answer has ``t == now``): one setpoint per tick, none computed from an older
        position than the last."""
        sp = v.setpoint
        return (
            sp is not None
            and sp.t < self.clock.now - 1e-6
            and v.mode.behaviour is Behaviour.EXTERNAL
            and v.index not in self._silent
        )

    async def _await_setpoints(self) -> None:
        """Lockstep: hold sim time until every streaming client answered this tick, at most
        ``lockstep_wall`` wall s; the clients still unanswered then are silent (not waited for
        until their next setpoint). The time-out runs from the hold's start, so a client
        that answered at once is never taken for silent because another one kept the tick."""
        waiting = set(self._unanswered())
        if not waiting:
            return
        self.lockstep_waits += 1
        deadline = time.monotonic() + self.config.lockstep_wall
        loop = asyncio.get_running_loop()
        # One future and one timer per wait (asyncio.wait_for would wrap a task around it).
        try:
            while waiting and not self._stop.is_set():
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    self._silent.update(waiting)
                    for i in sorted(waiting):
                        self.events.write(
                            self.clock.now,
                            "lockstep_silent",
                            vehicle=i,
                            wall=self.config.lockstep_wall,
                        )
                    return
                self._waiting = waiting  # _deliver takes each answer off
                held = self._held = loop.create_future()
                timer = loop.call_later(remaining, _resolve, held)
                try:
                    await held
                finally:
                    timer.cancel()
                waiting = set(self._unanswered())  # a vehicle may have joined meanwhile
        finally:
            self._held = None
            self._waiting = set()

    def _tick(self, dt: float) -> None:
        t = self.clock.now
        self.fleet.update_yaw(dt)
        vehicles = self.vehicles
        margins = [v.limits.fence_margin for v in vehicles]
        inside = inside_fences(self.scenario.area, self.fleet.pos, margins)
        for node, ok in zip(self.nodes, inside, strict=True):
            v = node.vehicle
            v.update()
            check_failsafes(v, ok and (not v.armed or breach(v) is None), dt)
        active = np.array([v.limits.sensor for v in vehicles], dtype=np.intp)
        radius = np.array([v.sensor_radius() for v in vehicles])
        readings = self.sensors.tick(t, self.fleet.pos, active, radius)
        tel = self.telemetry
        args, layouts, builders = tel.args, tel.layouts, tel.builders
        batch = tel.position_batch()
        for node in self.nodes:
            v = node.vehicle
            enc = node.encoder
            frame = enc.frame
            due = node.schedule.due(t)
            if HEARTBEAT not in due and node.early_heartbeat_due(t):
                due.insert(0, HEARTBEAT)
            if HEARTBEAT in due:
                v.state_changed = False
                node.last_heartbeat = t
            # What the vehicle's logic queued this tick (MISSION_CURRENT, ITEM_REACHED) goes
            # before the streams, which carry the state after it.
            frames = [enc.pack(msg) for msg in node.take_outbox()]
            for m in due:
                if m in POSITION_STREAMS:
                    frames.append(frame(m, batch[m][v.index]))
                    continue
                try:
                    layout = layouts.get(m)
                    if layout is None:
                        frames.append(enc.pack(builders[m](v)))
                    else:
                        frames.append(frame(m, layout.payload(args[m](v))))
                except (ValueError, OverflowError, struct.error):
                    # A state no field can carry (a vehicle flown thousands of km away):
                    # that one message is skipped; the vehicle and the others carry on.
                    self.telemetry_errors += 1
            reading = readings.get(v.index)
            if reading is not None:
                frames += self._sensor_frames(enc, reading, v.origin)
            if v.status:
                for severity, text in v.status:
                    frames.append(enc.pack(d.MAVLink_statustext_message(severity, text.encode())))
                v.status.clear()
            node.send_frames(frames)

    def _sensor_frames(self, enc: Encoder, r: Reading, origin: tuple[float, float]) -> list[bytes]:
        """The signal and the contacts, contacts in the vehicle's local frame (from its
        origin, as LOCAL_POSITION_NED)."""
        name = b"CNF" if r.confirms else b"DET"
        out = [enc.frame(NVF, signal_payload(self.clock.boot_ms, r.signal))]
        usec = self.clock.usec
        on, oe = origin
        out += [
            enc.frame(DEBUG_VECT, contact_payload(name, usec, n - on, e - oe, s))
            for _, n, e, s in r.contacts
        ]
        return out

    # ----- introspection
    def stats(self) -> dict[str, Any]:
        """Counters of every vehicle's links, the GCS link and the clock."""
        per = [node.stats.as_dict() for node in self.nodes]
        totals = {k: sum(p[k] for p in per) for k in per[0]} if per else {}
        return {
            "sim_time": self.clock.now,
            "clock_rebases": self.clock.rebases,
            "vehicles": per,
            "totals": totals,
            "gcs": self.gcs.stats.as_dict() if self.gcs else None,
            "events": self.events.count,
            "telemetry_errors": self.telemetry_errors,
            "tick_errors": self.tick_errors,
        }
