"""What one `companion fleet` run is asked to do."""

from __future__ import annotations

from dataclasses import MISSING, dataclass, fields
from pathlib import Path
from typing import Any

from companion.link.log_transfer import FLIGHT_LOG_WAIT_S


@dataclass(frozen=True)
class FleetOptions:
    """One fleet run on this machine."""

    profile: str
    out: Path
    vehicles: int | None = None
    """None: the profile's fleet size."""
    speedup: float = 100.0
    duration: float = 300.0
    backend: str = "pymavlink"
    persona: str = "px4"
    setpoints: str = "velocity"
    seed: int = 1
    base_port: int | None = None
    """First UDP port (refused when busy); None: a free block chosen by the fleet."""
    quiet: bool = True
    wall_limit: float = 900.0
    """Wall seconds after which the run is stopped as by one Ctrl-C (not complete)."""
    land_wait: float = 900.0
    """After a stop (Ctrl-C, wall limit), sim seconds the emulator keeps running so the vehicles
    can fly their end action and land; converted to wall seconds at the requested speed-up."""
    resume: bool = False
    """Continue the run in ``out``: companions whose mission log has no end record start again
    from it; the others stay ended (README "What a fleet run leaves on disk")."""
    mqtt_args: tuple[str, ...] = ()
    """--mqtt* flags passed to every companion (none: no MQTT unless the profile has it)."""
    signing_key_file: Path | None = None
    """MAVLink signing passphrase file for the emulator and the companions (they also inherit
    $MDM_MAVLINK_KEY)."""
    sensor_source: str | None = None
    """--sensor-source of every companion (None: the profile's sensor_source.kind)."""
    vehicles_file: Path | None = None
    """Fly the real (or SITL) vehicles this fleet file lists, no emulator (fleet/vehicles_file.py)."""
    sitl: str | None = None
    """Start one SITL instance per vehicle (arducopter, px4, mixed) and fly them, no emulator."""
    sitl_speedup: float = 1.0
    """Each SITL instance's speed-up (--sitl only)."""
    link_timeout: float = 30.0
    """Wall seconds each real vehicle has to answer on its link before the run is refused
    (--sitl: at least 60, the instances are still booting)."""
    web: tuple[str, ...] = ()
    """The `companion watch` flags of the live page started beside the run (--web ...); empty:
    none."""
    embedded_broker: bool = False
    """The page runs the embedded MQTT broker for the run (--web without --mqtt or a profile's
    mqtt:); the companions connect to it with accounts of their own (mdm_ground.broker)."""
    gcs: str | None = None
    """``udpout:HOST:PORT``: the emulator also sends every vehicle's MAVLink there (a ground
    station); the companions then leave the vehicles' streams on."""
    flight_log_wait: float = FLIGHT_LOG_WAIT_S
    """Real vehicles (fleet file, --sitl): wall seconds each companion spends downloading its
    autopilot's own log once landed (`companion run --flight-log-wait`); 0: none."""
    lockstep: bool = True
    """The emulator holds sim time until every companion answered the last position
    (sim-vehicle --lockstep): a loaded host slows the run instead of the companions skipping
    stale positions, so setpoints stay at the telemetry rate (10 Hz) in vehicle time. Costs
    speed (docs/companion.md). Always on flat out (speedup 0)."""


def default(name: str) -> Any:
    """The default of option ``name``: the one source the command line takes its defaults from."""
    (found,) = (f.default for f in fields(FleetOptions) if f.name == name)
    if found is MISSING:
        raise KeyError(f"FleetOptions.{name} has no default")
    return found
