"""Fly one vehicle from Python: what `companion run` wires (mission log, MQTT tee, swarm peers,
sensor source), as an async context manager the CLI, the tests and a user's script share.

    async with fly(load_profile("paper-fixed"), 0, PymavlinkLink(url=..., target_system=1),
                   duration=120.0, log_dir=Path("runs")) as flight:
        print(await flight.ended())

Leaving the block before the mission ended ends it as one SIGINT does (end action, wait for the
landing); an exception in the block stops commanding at once.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import AsyncIterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from companion.errors import InputError
from companion.fence_from_profile import guidance_fence, own_frame_reach, site_geometry
from companion.link.base import VehicleLink
from companion.mission import MissionConfig, VehicleMission
from companion.mission.core_for import LAWNMOWER_KINDS, is_swarm
from companion.mission.lawnmower_core import LawnmowerCore
from companion.mission.start_point import start_point
from companion.mission.study_only import study_only_refusal
from companion.mission.swarm_core import SwarmCore, live_swarm_refusal
from companion.sensors.factory import DetectorFeed, make_sensor_source
from companion.telemetry import EventSink, MissionLog, read_log
from companion.telemetry.tee_sink import TeeSink
from mdm_profiles import MissionProfile, SensorSourceKind
from mdm_profiles.mqtt_spec import MqttSpec

if TYPE_CHECKING:
    from companion.telemetry.mqtt.swarm_peers import SwarmPeers
    from companion.telemetry.mqtt.vehicle_telemetry import VehicleTelemetry

log = logging.getLogger(__name__)

STOPPED_BY_SECOND_SIGNAL = "stopped by a second signal"
"""What :meth:`Flight.ended` returns when a second stop cut the end action short."""
REFUSED = "refused: "
"""How :meth:`Flight.ended` begins when the companion would not start the vehicle (too far
outside the profile's area)."""


@dataclass
class Flight:
    """A mission in flight."""

    mission: VehicleMission
    """Its state (``phase``, ``snapshot()``) and the operator's requests (``operator_pause`` ...)."""
    task: asyncio.Task[str]

    async def ended(self) -> str:
        """Wait for the end; why it ended (``mission time``, ``operator``, ...)."""
        return await asyncio.shield(self.task)

    def stop(self) -> None:
        """As a SIGINT: the first call ends the mission with its end action and waits for the
        landing; a second stops commanding at once."""
        self.mission.operator_stop()


def check_flight(config: MissionConfig, mqtt: MqttSpec | None, source: SensorSourceKind) -> None:
    """Refuse, naming what is missing, a flight that cannot run (raises InputError)."""
    vehicles = config.profile.fleet.vehicles
    if not 0 <= config.vehicle < vehicles:
        raise InputError(f"vehicle {config.vehicle}: profile has {vehicles} vehicles")
    if mqtt is None and is_swarm(config):
        raise InputError(
            f"profile {config.profile.name!r}: policy.kind {config.profile.policy.kind!r} "
            "shares the swarm's bests over MQTT; configure a broker (--mqtt HOST[:PORT] or "
            "the profile's mqtt: section)"
        )
    refusal = live_swarm_refusal(config.profile) if is_swarm(config) else None
    if refusal is not None:
        raise InputError(refusal)
    if config.profile.policy.kind in LAWNMOWER_KINDS:
        try:  # the strip inside the guidance fence, before any socket is opened
            LawnmowerCore(
                config.profile, config.seed, config.vehicle, guidance_fence(config.profile)
            )
        except ValueError as exc:
            raise InputError(
                f"profile {config.profile.name!r}, vehicle {config.vehicle}: {exc}"
            ) from None
    refusal = study_only_refusal(config.profile)
    if refusal is not None:
        raise InputError(refusal)
    if source == "mqtt" and mqtt is None:
        raise InputError(
            "sensor source 'mqtt' reads detections from a broker; configure one "
            "(--mqtt HOST[:PORT] or the profile's mqtt: section)"
        )


@contextlib.asynccontextmanager
async def fly(
    profile: MissionProfile,
    vehicle: int,
    link: VehicleLink,
    *,
    mqtt: MqttSpec | None = None,
    sensor_source: SensorSourceKind | None = None,
    **options: Any,
) -> AsyncIterator[Flight]:
    """Fly ``vehicle`` of ``profile`` over ``link`` (not yet opened); ``options`` are
    :class:`MissionConfig` fields (``duration``, ``log_dir``, ``end_action``, ...); ``mqtt``
    tees the events to a broker; ``sensor_source`` defaults to the profile's.

    Raises:
        InputError: the flight cannot run as asked (a vehicle the profile does not have, a
            swarm policy or an MQTT sensor source without a broker, swarm settings or a
            study-only policy.redetection the live companion does not fly); raised before any socket or file is opened.
        LogFormatError: the vehicle's mission log (read to resume) was written by another
            version.
        TypeError: ``options`` holds a name that is not a MissionConfig field.
        OSError: the mission log's folder cannot be written.
    The mission itself ends with a reason (:meth:`Flight.ended`), not an error: a refused
    command, a lost link or a failsafe are recorded in the mission log and its ``exit``.
    """
    config = MissionConfig(vehicle=vehicle, profile=profile, **options)
    source: SensorSourceKind = sensor_source or profile.sensor_source.kind
    check_flight(config, mqtt, source)
    recovered = read_log(config.mission_log_path())
    if recovered.confirmed:
        log.info(
            "resuming with %d confirmed target(s) from %s",
            len(recovered.confirmed),
            config.mission_log_path(),
        )
    mission_log = MissionLog(config.mission_log_path())
    try:
        sink: EventSink = mission_log
        telemetry: VehicleTelemetry | None = None
        if mqtt is not None:  # no broker configured: no MQTT code at all
            from companion.telemetry.mqtt.vehicle_telemetry import VehicleTelemetry

            telemetry = VehicleTelemetry.open(
                mqtt, profile_name=profile.name, vehicle=vehicle, log_dir=config.log_dir
            )
            sink = TeeSink(mission_log, telemetry)
        peers: SwarmPeers | None = None
        if telemetry is not None and is_swarm(config):
            from companion.telemetry.mqtt.swarm_peers import SwarmPeers

            swarm = profile.policy.swarm
            peers = SwarmPeers(
                telemetry.channel,
                telemetry.topics.prefix,
                vehicle,
                profile.fleet.vehicles,
                delay=swarm.message_delay,
                drop=swarm.message_drop,
                seed=config.seed,
            )
        feed = None
        if telemetry is not None:
            feed = DetectorFeed(telemetry.channel, telemetry.topics.detections)
        sensors = make_sensor_source(
            source, profile=profile, seed=config.seed, link=link, feed=feed
        )
        log.info("vehicle %d: sensor source %s", vehicle, source)
        site = site_geometry(profile)  # the frame and fences, built once for the whole flight
        start, own_fence = None, None
        if profile.site is not None:  # geo-referenced: flown in its own frame, from its start
            link.use_profile_frame(site.frame)
            start = start_point(profile, config.seed, vehicle, site.guidance)
            own_fence = [(p.lat, p.lon) for p in profile.site.geofence]
        else:  # the area at the profile's origin, unless the vehicle booted far from it
            link.use_profile_frame(site.frame, own_frame_reach(profile))
        mission = VehicleMission(
            config,
            link,
            sink,
            recovered=recovered,
            fence=site.guidance,
            peers=peers,
            sensors=sensors,
            watch=site.watch,
            start=start,
            own_fence=own_fence,
        )
        task = asyncio.create_task(_run(mission, telemetry, peers), name=f"v{vehicle}-flight")
        try:
            yield Flight(mission, task)
            if not task.done():
                mission.operator_stop()
            await task
        finally:
            if not task.done():
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await task
    finally:
        mission_log.close()


async def _run(
    mission: VehicleMission, telemetry: VehicleTelemetry | None, peers: SwarmPeers | None
) -> str:
    """The mission with its MQTT telemetry and swarm exchange around it."""
    try:
        async with telemetry.running(mission) if telemetry else contextlib.nullcontext():
            if peers is None:
                return await mission.run()
            sender = asyncio.create_task(peers.run(), name=f"v{mission.config.vehicle}-swarm")
            try:
                return await mission.run()
            finally:
                sender.cancel()
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(peers.flush(), 2.0)
                core = mission.core
                assert isinstance(core, SwarmCore)
                mission.emit(
                    "swarm",
                    sent=peers.sent,
                    received=peers.received,
                    dropped=peers.dropped,
                    rejected=peers.rejected,
                    iterations=core.iterations,
                    peer_bests_used=core.peer_bests_used,
                )
    except asyncio.CancelledError:  # a second stop: the mission's task was cancelled
        return STOPPED_BY_SECOND_SIGNAL
