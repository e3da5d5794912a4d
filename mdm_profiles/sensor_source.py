"""The optional ``sensor_source:`` section of a profile: where a companion's target readings come
from (the sensors themselves, radii and order, are the profile's ``sensors`` list)."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

SensorSourceKind = Literal["mavlink", "virtual", "mqtt"]


class SensorSourceSpec(BaseModel):
    """``kind``: ``mavlink`` (readings the vehicle sends: the emulator's DEBUG_VECT), ``virtual``
    (the companion reads the profile's targets against the vehicle's position with the paper's
    sensor model: SITL and field rehearsal), ``mqtt`` (an onboard detector publishes on
    ``<prefix>/uav<i>/detections``, docs/mqtt.md)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    kind: SensorSourceKind = "mavlink"
    silence_timeout: float = Field(
        default=5.0,
        gt=0,
        description="mqtt: a detector that publishes nothing for this long (wall s) is reported.",
    )
    min_confidence: float = Field(
        default=0.0, ge=0, le=1, description="mqtt: detections with a lower confidence are ignored."
    )
