"""Configuration of one vehicle's mission (frozen; built by the CLI from a profile and flags)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from companion.autopilots import FlightMode
from companion.link.base import SetpointKind
from companion.link.log_transfer import FLIGHT_LOG_WAIT_S
from companion.mission.battery_reserve import ReserveRule
from mdm_profiles import MissionProfile


@dataclass(frozen=True)
class MissionConfig:
    """Everything one companion needs besides its link."""

    vehicle: int
    """0-based index in the profile; its system id is ``target_system``, else vehicle + 1."""
    profile: MissionProfile
    setpoints: SetpointKind = "velocity"
    """Velocity setpoints by pursuit guidance, or the waypoint as a position setpoint."""
    seed: int = 0
    """Base seed; the vehicle's Generator is seeded with (seed, vehicle)."""
    log_dir: Path = Path("runs")
    """Where mission-<i>.jsonl and vehicle-<i>.tlog go."""
    duration: float | None = None
    """Search time in vehicle seconds; None = profile.mission.duration."""
    end_action: FlightMode = FlightMode.RTL
    """RTL or LAND at the end of the mission."""
    battery_min: float = 20.0
    """End the mission below this remaining battery, percent."""
    battery_reserve: ReserveRule | None = None
    """Also end it when what is left is what the flight home needs plus a reserve
    (battery_reserve.py); None: the fixed minimum only (profiles without a site)."""
    link_timeout: float = 3.0
    """Wall seconds without HEARTBEAT before the link counts as lost (vehicle time stops with
    the link, so this one timer cannot be in vehicle time)."""
    heartbeat_period: float = 1.0
    """Companion HEARTBEAT period, wall seconds."""
    waiting_line_period: float = 5.0
    """Wall seconds between 'waiting for system N' lines while the vehicle is not heard."""
    land_wait: float = 600.0
    """Vehicle seconds to wait for touchdown after the end action; 0 = exit at once."""
    flight_log_wait: float = FLIGHT_LOG_WAIT_S
    """Wall seconds to download the autopilot's own log once landed (log_transfer.py); 0 =
    none."""
    climb_timeout: float = 120.0
    """Vehicle seconds allowed to reach the search altitude before the mission is aborted."""
    dedicated_link: bool = False
    """The link carries only this companion (no ground station on it): streams the mission does
    not read may be switched off to save CPU (the fleet's emulator links)."""
    max_speedup: float | None = None
    """Vehicle seconds per wall second the vehicle's clock may run (the speed-up asked of a
    simulator, with its margin): positions whose clock leaps further are dropped. None: not
    known; a leap of more than 5 vehicle s is taken only when 3 positions in a row agree."""
    stop_when_all_found: bool = True
    """End when this vehicle has confirmed as many targets as the profile declares real."""
    target_system: int | None = None
    """The vehicle's MAVLink system id (1-255) when it is not vehicle + 1 (a real fleet's ids)."""

    @property
    def system_id(self) -> int:
        return self.target_system if self.target_system is not None else self.vehicle + 1

    @property
    def altitude(self) -> float:
        """This vehicle's altitude above home (Assumption III: vertical separation)."""
        fleet = self.profile.fleet
        return fleet.altitude + self.vehicle * fleet.altitude_step

    @property
    def search_duration(self) -> float:
        return self.duration if self.duration is not None else self.profile.mission.duration

    def mission_log_path(self) -> Path:
        return self.log_dir / f"mission-{self.vehicle}.jsonl"

    def tlog_path(self) -> Path:
        return self.log_dir / f"vehicle-{self.vehicle}.tlog"

    def autopilot_log_stem(self) -> Path:
        """The autopilot's own log, without its suffix (.bin, .ulg)."""
        return self.log_dir / f"autopilot-{self.vehicle}"
