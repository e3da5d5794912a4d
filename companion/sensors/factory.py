"""The sensor source a mission flies with: the profile's ``sensor_source.kind`` or the flag's."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, get_args

from companion.link.base import VehicleLink
from companion.sensors.base import SensorSource
from companion.sensors.mavlink_source import MavlinkSensorSource
from companion.sensors.virtual_source import VirtualSensorSource
from mdm_profiles import MissionProfile, SensorSourceKind

if TYPE_CHECKING:  # no MQTT code is loaded without a broker
    from companion.telemetry.mqtt.channel import MqttChannel

SENSOR_SOURCES: tuple[str, ...] = get_args(SensorSourceKind)


@dataclass(frozen=True)
class DetectorFeed:
    """Where an MQTT detector's messages arrive: the companion's broker connection and topic."""

    channel: MqttChannel
    topic: str


def make_sensor_source(
    kind: SensorSourceKind,
    *,
    profile: MissionProfile,
    seed: int,
    link: VehicleLink,
    feed: DetectorFeed | None,
) -> SensorSource:
    """``mavlink``: the vehicle's readings; ``virtual``: the profile's targets (same ``seed``,
    same targets as the emulator); ``mqtt``: ``feed`` (a broker is required)."""
    if kind == "mavlink":
        return MavlinkSensorSource(link, len(profile.sensors))
    if kind == "virtual":
        return VirtualSensorSource(profile, seed)
    if feed is None:
        raise ValueError(
            "sensor source 'mqtt' reads detections from a broker; configure one "
            "(--mqtt HOST[:PORT] or the profile's mqtt: section)"
        )
    from companion.sensors.mqtt_source import MqttSensorSource

    return MqttSensorSource(feed.channel, feed.topic, profile)
