"""The vehicles of a fleet run that does not start the emulator: those of a fleet file
(--vehicles-file) or SITL instances the run starts itself (--sitl), each probed on its link
before any companion starts."""

from __future__ import annotations

from dataclasses import dataclass, field

from mdm_ground.fleet.link_probe import probe_vehicles
from mdm_ground.fleet.options import FleetOptions
from mdm_ground.fleet.preflight import FleetInputError
from mdm_ground.fleet.sitl_team import SitlVehicle, start_team
from mdm_ground.fleet.vehicles_file import VehicleEntry, load_vehicles_file
from mdm_profiles import MissionProfile

SITL_PROBE_S = 60.0
"""At least this long for a SITL instance to answer: it is still booting."""


@dataclass
class Team:
    """Real vehicles by profile index; the SITL instances this run started (stopped at the end)."""

    entries: dict[int, VehicleEntry]
    autopilots: dict[int, str]
    """What each vehicle's HEARTBEAT said it is (arducopter, px4)."""
    sitl: list[SitlVehicle] = field(default_factory=list)

    def stop(self) -> None:
        """Stop every SITL instance this run started (none for a fleet file)."""
        for member in self.sitl:
            member.stop()


def is_real(o: FleetOptions) -> bool:
    """The run flies real or SITL vehicles, not the emulator's."""
    return o.vehicles_file is not None or o.sitl is not None


def team_size(o: FleetOptions, profile: MissionProfile) -> int | None:
    """A fleet file's vehicle count (checked against --vehicles), else None (--vehicles or the
    profile's count decides)."""
    if o.vehicles_file is None:
        return None
    if o.sitl is not None:
        raise FleetInputError(
            "--vehicles-file and --sitl: choose one (a file lists vehicles "
            "that run already; --sitl starts its own)"
        )
    entries = load_vehicles_file(o.vehicles_file, profile)
    if o.vehicles is not None and o.vehicles != len(entries):
        raise FleetInputError(
            f"--vehicles {o.vehicles}: --vehicles-file {o.vehicles_file} lists {len(entries)}"
        )
    return len(entries)


def open_team(o: FleetOptions, profile: MissionProfile, vehicles: int) -> Team:
    """Start the SITL instances (--sitl) or read the fleet file, then probe every link."""
    sitl: list[SitlVehicle] = []
    if o.sitl is not None:
        sitl = start_team(profile, o.seed, list(range(vehicles)), o.sitl, o.sitl_speedup, o.out)
        entries = [s.entry for s in sitl]
        timeout = max(o.link_timeout, SITL_PROBE_S)
    else:
        assert o.vehicles_file is not None
        entries = load_vehicles_file(o.vehicles_file, profile)
        timeout = o.link_timeout
    try:
        autopilots = probe_vehicles(entries, timeout)
    except BaseException:
        for member in sitl:
            member.stop()
        raise
    return Team({e.index: e for e in entries}, autopilots, sitl)
