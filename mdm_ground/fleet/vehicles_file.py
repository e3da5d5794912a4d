"""The fleet file of `companion fleet --vehicles-file`: which real (or SITL) vehicles fly which
vehicle of the profile, over which link, with which MAVLink system id (docs/companion.md,
"Flying real vehicles"). Validated like a profile: every problem names the file, the vehicle
entry and what is allowed."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from companion.link.factory import BACKENDS
from companion.sensors.factory import SENSOR_SOURCES
from mdm_ground.fleet.preflight import FleetInputError
from mdm_profiles import MissionProfile

Autopilot = Literal["arducopter", "px4"]


class VehicleEntry(BaseModel):
    """One vehicle of the fleet."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    index: int = Field(ge=0, description="The vehicle's 0-based index in the profile.")
    link: str = Field(
        min_length=1, description="Link URL, e.g. tcp:10.0.0.5:5760, udpin:0.0.0.0:14540."
    )
    system_id: int = Field(ge=1, le=255, description="The vehicle's MAVLink system id.")
    autopilot: Autopilot | None = Field(
        default=None, description="Checked against the vehicle's HEARTBEAT before start."
    )
    backend: str | None = Field(default=None, description=f"One of {', '.join(BACKENDS)}.")
    sensor_source: str | None = Field(
        default=None, description=f"One of {', '.join(SENSOR_SOURCES)}."
    )

    def name(self) -> str:
        return f"vehicle {self.index} (system {self.system_id}, {self.link})"


class _FleetFile(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    vehicles: list[VehicleEntry] = Field(min_length=1)


def _choice(value: str | None, allowed: tuple[str, ...], what: str, where: str) -> None:
    if value is not None and value not in allowed:
        raise FleetInputError(f"{where}: {what} {value!r}: one of {', '.join(allowed)}")


def check_entries(entries: list[VehicleEntry], profile: MissionProfile, source: str) -> None:
    """Vehicles 0..N-1 of the profile once each, every system id and link once, known
    backends and sensor sources; FleetInputError naming the vehicle otherwise."""
    seen: dict[str, dict[object, int]] = {"index": {}, "system_id": {}, "link": {}}
    for k, e in enumerate(entries):
        where = f"{source}: vehicles[{k}] ({e.name()})"
        if e.index >= profile.fleet.vehicles:
            raise FleetInputError(
                f"{where}: index {e.index}: profile {profile.name!r} has "
                f"{profile.fleet.vehicles} vehicles (0..{profile.fleet.vehicles - 1})"
            )
        for what, value in (("index", e.index), ("system_id", e.system_id), ("link", e.link)):
            earlier = seen[what].setdefault(value, k)
            if earlier != k:
                raise FleetInputError(
                    f"{where}: {what} {value!r} already used by vehicles[{earlier}]"
                )
        _choice(e.backend, BACKENDS, "backend", where)
        _choice(e.sensor_source, SENSOR_SOURCES, "sensor_source", where)
    missing = sorted(set(range(len(entries))) - set(seen["index"]))
    if missing:
        raise FleetInputError(
            f"{source}: {len(entries)} vehicles must be the profile's vehicles 0..{len(entries) - 1} "
            f"(as --vehicles {len(entries)} flies); no entry has index {missing[0]}"
        )


def load_vehicles_file(path: Path, profile: MissionProfile) -> list[VehicleEntry]:
    """The checked entries of ``path`` (FleetInputError: the file, the entry, the rule)."""
    source = f"--vehicles-file {path}"
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise FleetInputError(f"{source}: cannot read ({exc.strerror})") from None
    except yaml.YAMLError as exc:
        raise FleetInputError(f"{source}: not valid YAML: {exc}") from None
    if not isinstance(data, dict):
        raise FleetInputError(f"{source}: a fleet file is a YAML mapping with a 'vehicles:' list")
    try:
        entries = list(_FleetFile.model_validate(data).vehicles)
    except ValidationError as exc:
        lines = [f"{source}: invalid fleet file ({exc.error_count()} problem(s))"]
        for item in exc.errors():
            field = ".".join(str(p) for p in item["loc"]) or "(top level)"
            given = item.get("input")
            shown = "" if isinstance(given, dict | list) else f" (got {given!r})"
            lines.append(f"  {field}: {item['msg']}{shown}")
        raise FleetInputError("\n".join(lines)) from None
    check_entries(entries, profile, source)
    return entries
