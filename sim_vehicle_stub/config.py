"""Configuration of one emulator process."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from mdm_core.ports import GCS_UDP, TCP_BASE, TCP_STRIDE, VEHICLE_OWN_UDP_BASE, VEHICLE_UDP_BASE
from mdm_profiles import MissionProfile

SYSID_SPACE = 254
"""MAVLink system ids 1..254 (255 is the GCS). Vehicle i is system ``i % 254 + 1``: ids repeat in
blocks of 254, every vehicle keeping its own UDP port (and TCP port), so one link never carries
two vehicles with the same id. The one shared link, the GCS output, allows one block only."""
MAX_PORT = 65535


def system_id(index: int) -> int:
    """MAVLink system id of vehicle ``index`` (0-based)."""
    return index % SYSID_SPACE + 1


@dataclass(frozen=True)
class EmulatorConfig:
    """Everything `sim-vehicle` takes from the command line; defaults match PX4 SITL."""

    profile: MissionProfile
    vehicles: int | None = None
    """Number of vehicles; None takes the profile's fleet size."""
    personas: tuple[str, ...] = ("px4",)
    """Persona per vehicle, cycled when shorter than the fleet."""
    host: str = "127.0.0.1"
    """Where the vehicles send first (the companions' address)."""
    base_port: int = VEHICLE_UDP_BASE
    """Vehicle i sends first to host:base_port+i."""
    bind_host: str = "127.0.0.1"
    bind_port_base: int = VEHICLE_OWN_UDP_BASE
    """Vehicle i's own UDP port is bind_port_base+i; 0 picks free ports."""
    tcp: bool = False
    tcp_base: int = TCP_BASE
    """TCP server of vehicle i on tcp_base + 10 i."""
    gcs: bool = False
    gcs_port: int = GCS_UDP
    gcs_host: str | None = None
    """Where the --gcs output goes (None: ``host``)."""
    speedup: float | None = 1.0
    """Sim seconds per wall second; None runs as fast as possible."""
    sim_step: float = 0.05
    """Physics step, sim s (the lag model is discretised exactly, so this only sets latency)."""
    telemetry_hz: float = 10.0
    """Rate of position/attitude streams and sensor readings, per sim second."""
    lockstep: bool = False
    """Hold sim time at each telemetry tick until every vehicle flown in the external mode
    (OFFBOARD / GUIDED) by a streaming client has answered that tick's telemetry: a loaded
    host then slows the sim instead of letting the vehicles fly on stale setpoints. A
    client that leaves a held tick unanswered for ``lockstep_wall`` wall s is not waited for
    again until its next setpoint (the failsafes act)."""
    lockstep_wall: float = 0.25
    seed: int = 0
    events: Path | None = None
    battery_endurance: float = 7200.0
    scale_timeouts: bool = True
    """Multiply failsafe time-out defaults by the speed-up so wall-clock clients keep working."""
    flood_rate: float = 5000.0
    """Datagrams per wall second accepted per endpoint; more are dropped unread."""
    start_positions: tuple[tuple[float, float], ...] | None = None
    """Override the profile's periphery start points, metres (north, east)."""
    signing_key: bytes | None = field(default=None, repr=False)
    """MAVLink 2 signing secret (32 bytes); None: signing off. From a key file or the
    environment (mavlink_wire.load_signing_key), never from the profile."""

    def __post_init__(self) -> None:
        n = self.fleet_size
        if n < 1:
            raise ValueError(f"vehicles must be >= 1, got {n}")
        if self.gcs and n > SYSID_SPACE:
            raise ValueError(
                f"--gcs carries every vehicle on one link, so at most {SYSID_SPACE} vehicles "
                f"(system ids 1..254; 255 is the GCS), got {n}; without --gcs system ids "
                "repeat every 254 vehicles, each vehicle on its own port"
            )
        ports = [("base_port", self.base_port, n - 1)]
        if self.bind_port_base:
            ports.append(("bind_port_base", self.bind_port_base, n - 1))
        if self.tcp:
            ports.append(("tcp_base", self.tcp_base, TCP_STRIDE * (n - 1)))
        for name, base, span in ports:
            if not (base >= 1 and base + span <= MAX_PORT):
                raise ValueError(
                    f"{name} {base} with {n} vehicles needs ports up to {base + span}; "
                    f"UDP/TCP ports stop at {MAX_PORT}"
                )
        if self.telemetry_hz <= 0 or self.sim_step <= 0:
            raise ValueError("telemetry_hz and sim_step must be > 0")
        if self.signing_key is not None and len(self.signing_key) != 32:
            raise ValueError(f"signing key of {len(self.signing_key)} bytes; need 32")

    @property
    def fleet_size(self) -> int:
        return self.vehicles if self.vehicles is not None else self.profile.fleet.vehicles

    def persona_of(self, index: int) -> str:
        return self.personas[index % len(self.personas)]
