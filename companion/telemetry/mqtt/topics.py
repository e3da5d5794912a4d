"""The topic tree: <prefix>/uav<i>/state|event|status|cmd|detections and <prefix>/all/cmd (default prefix mdm/<profile>)."""

from __future__ import annotations

from dataclasses import dataclass


def default_prefix(profile_name: str) -> str:
    return f"mdm/{profile_name}"


@dataclass(frozen=True)
class VehicleTopics:
    """The topics of one vehicle under ``prefix``."""

    prefix: str
    vehicle: int

    @property
    def name(self) -> str:
        """The vehicle's topic level (also its broker account in docker/mosquitto)."""
        return f"uav{self.vehicle}"

    def _topic(self, leaf: str) -> str:
        return f"{self.prefix}/{self.name}/{leaf}"

    @property
    def state(self) -> str:
        return self._topic("state")

    @property
    def event(self) -> str:
        return self._topic("event")

    @property
    def status(self) -> str:
        return self._topic("status")

    @property
    def cmd(self) -> str:
        return self._topic("cmd")

    @property
    def detections(self) -> str:
        """Where the vehicle's onboard detector publishes (the ``mqtt`` sensor source)."""
        return self._topic("detections")

    @property
    def fleet_cmd(self) -> str:
        """Commands for every vehicle under the prefix."""
        return f"{self.prefix}/all/cmd"
