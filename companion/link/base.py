"""The link interface every MAVLink backend implements (pymavlink, MAVSDK), and what they share:
the profile's frame, the vehicle's origin and fence, the vehicle's own words (STATUSTEXT); the
stream negotiation (stream_requests.py), the speed limit (speed_policy.py) and the sensor switch
(sensor_parameter.py) are its parts, the search's fast path its hook (position_answerer.py)."""

from __future__ import annotations

import asyncio
import math
import time
from abc import ABC, abstractmethod
from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import Literal

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.autopilots import Autopilot, FlightMode
from companion.guidance import NedSetpoint
from companion.link.errors import LinkError
from companion.link.fence_protocol import FenceTransferError
from companion.link.local_frame import LocalFrame
from companion.link.log_transfer import FlightLog
from companion.link.messages import GlobalPosition, LinkEvent, LocalPosition
from companion.link.outcome import CommandResult, Outcome
from companion.link.position_answerer import PositionAnswerer
from companion.link.sensor_parameter import SensorParameter
from companion.link.speed_policy import SpeedPolicy
from companion.link.stream_requests import StreamRequests
from companion.link.streams import StreamWatch
from companion.link.telemetry_guard import TelemetryGuard
from companion.link.vehicle_frame import FrameAlignment

__all__ = ["LinkError", "SetpointKind", "VehicleLink"]
"""LinkError: the interface's error, named here for the code that uses the interface."""

SetpointKind = Literal["velocity", "position"]

_REASON_WAIT_S = 0.3
"""How long a refusal waits for the STATUSTEXT that explains it: ArduPilot queues the text
before the COMMAND_ACK, but sends it from its text queue, which can come out after the ack."""


class VehicleLink(StreamRequests, SpeedPolicy, SensorParameter, ABC):
    """One vehicle over MAVLink: events in (``events``), commands and setpoints out.

    A backend parses what it receives into :mod:`companion.link.messages` events on
    ``events``; the mission reads nothing else. Commands return a
    :class:`~companion.link.outcome.CommandResult`: truthy when accepted, else denied (with the
    vehicle's STATUSTEXT reason where it sent one) or timed out.
    """

    events: asyncio.Queue[LinkEvent]
    autopilot: Autopilot | None
    """Set from the first HEARTBEAT of the vehicle."""
    target_system: int
    own_system: int = 245
    """The companion's own system id (its HEARTBEAT's): the GCS ArduCopter's failsafe watches."""
    uploads_fence: bool = False
    """The backend implements :meth:`upload_fence` and :meth:`download_fence`."""
    alignment: FrameAlignment | None = None
    """Set by :meth:`use_profile_frame`: positions in and position setpoints out are in the
    profile's frame, whatever the vehicle's own local origin."""
    _origin: tuple[float, float, float] | None = None
    """The latest GPS_GLOBAL_ORIGIN (lat, lon, alt AMSL), aligned or not."""

    def __init__(self) -> None:
        self.events = asyncio.Queue()
        self.listener: Callable[[list[LinkEvent]], None] | None = None
        """Takes the events instead of ``events`` once set (the mission's decision loop): each
        batch read in one callback, at once, without a queue and a task switch per position."""
        self.answerer: PositionAnswerer | None = None
        """Set with ``listener`` by the decision loop: a backend may hand it a position (with the
        other events of its datagram) instead of publishing them, when ``ready`` says so."""
        self.autopilot = None
        self.streams = StreamWatch()
        self.guard = TelemetryGuard()
        """The check of every position taken (telemetry_guard.py); the mission sets its limits."""
        self.heard: set[int] = set()
        """System ids heard on this link (any sender), for the 'waiting for system N' line."""
        self._texts: deque[tuple[float, int, str]] = deque(maxlen=32)
        self._param_known: dict[str, bool] = {}
        self._home: tuple[float, float, float, float, float] | None = None
        """The latest HOME_POSITION (lat, lon, alt, x, y), for :meth:`learn_origin`."""

    def publish(self, batch: list[LinkEvent]) -> None:
        """Hand received events over, in arrival order: to ``listener``, else onto ``events``."""
        if self.listener is not None:
            self.listener(batch)
            return
        for event in batch:
            self.events.put_nowait(event)

    @abstractmethod
    def describe(self) -> str:
        """The URL the link listens on or connects to."""

    @abstractmethod
    async def open(self) -> None:
        """Start listening / connect. Does not wait for the vehicle.

        Raises:
            LinkError: the address cannot be bound or connected to (a port taken, a TCP
                endpoint not up yet); the mission retries with backoff.
        """

    @abstractmethod
    async def close(self) -> None:
        """Release sockets and logs; safe to call twice."""

    async def configure_streams(self) -> None:
        """Ask the vehicle to stop streams the companion does not read (a dedicated link only:
        a ground station sharing the link would lose them). Default: leave them."""
        return

    async def reconnect(self) -> None:
        """Drop and re-open the transport after a link loss."""
        await self.close()
        await self.open()

    @abstractmethod
    def send_heartbeat(self) -> None:
        """One HEARTBEAT of the companion (MAV_TYPE_ONBOARD_CONTROLLER)."""

    @abstractmethod
    def send_setpoint(self, setpoint: NedSetpoint, kind: SetpointKind) -> None:
        """A velocity (with altitude-hold vd) or a position setpoint, local NED."""

    async def begin_setpoints(self) -> None:
        """Called once the vehicle is airborne in the guided mode, before the search's
        setpoints (MAVSDK on ArduPilot starts its Offboard stream here, not before takeoff)."""
        return

    @abstractmethod
    async def set_mode(self, mode: FlightMode) -> CommandResult:
        """Ask for a flight mode."""

    @abstractmethod
    async def arm(self) -> CommandResult:
        """Arm the motors."""

    @abstractmethod
    async def takeoff(self, altitude: float) -> CommandResult:
        """Climb to ``altitude`` m above home (autopilots that need a command for it)."""

    @abstractmethod
    async def command_long(self, command: int, *params: float) -> CommandResult:
        """COMMAND_LONG to the autopilot, retried until a final COMMAND_ACK."""

    @abstractmethod
    def request_data_stream(self, stream_id: int, rate_hz: int) -> None:
        """REQUEST_DATA_STREAM (no answer comes back; older ArduPilot needs it)."""

    @abstractmethod
    async def read_param(self, name: str) -> float | None:
        """PARAM_REQUEST_READ; the value, or None when the vehicle does not answer."""

    @abstractmethod
    async def set_param(self, name: str, value: float, param_type: int) -> float | None:
        """PARAM_SET; the value the vehicle echoed (it may clamp it), None without an echo."""

    # -- frames: the only place converting the vehicle's frame to the profile's ----------

    @property
    def global_position(self) -> bool:
        """The mission also reads GLOBAL_POSITION_INT (the fence watch on the GPS position of
        a geo-referenced profile)."""
        return self.alignment is not None and self.alignment.reach is None

    def use_profile_frame(self, profile: LocalFrame, reach: float | None = None) -> None:
        """Fly in the profile's frame: positions are held back until the vehicle's origin is
        known (:meth:`learn_origin`), then shifted; GLOBAL_POSITION_INT becomes events.
        ``reach`` (a profile without ``site``): an origin farther than that from the
        profile's is flown in the vehicle's own frame instead (a SITL booted elsewhere)."""
        self.alignment = FrameAlignment(profile, reach)

    def _profile_xy(self, x: float, y: float) -> tuple[float, float]:
        """A point of the vehicle's local frame (a sensor contact) in the profile's."""
        a = self.alignment
        return (x, y) if a is None else a.to_profile(x, y)

    def _local(
        self,
        component: int,
        t: float,
        x: float,
        y: float,
        z: float,
        vx: float,
        vy: float,
        vz: float,
        received: float,
    ) -> LocalPosition | None:
        """A LOCAL_POSITION_NED as an event in the profile's frame (None while unaligned, and
        for what ``guard`` drops)."""
        a = self.alignment
        if a is not None and a.origin is None:
            return None
        north, east = (x, y) if a is None else (x + a.north, y + a.east)
        if not self.guard.local(component, t, north, east, z, vx, vy, vz, received):
            return None
        return LocalPosition(t, north, east, z, vx, vy, vz, received)

    def _global(
        self, component: int, t: float, lat: float, lon: float, relative_alt: float
    ) -> GlobalPosition | None:
        """A GLOBAL_POSITION_INT as an event (only when flying in the profile's frame; None
        for what ``guard`` drops)."""
        a = self.alignment
        if a is None:
            return None
        self.streams.note("GLOBAL_POSITION_INT", t)
        if lat == 0.0 and lon == 0.0:  # no position yet (ArduPilot before its EKF origin)
            return None
        n = e = math.nan
        if math.isfinite(lat) and math.isfinite(lon) and abs(lat) <= 90.0 and abs(lon) <= 180.0:
            n, e, _ = a.profile.to_local(lat, lon, a.profile.alt)
        if not self.guard.global_position(
            component, t, lat, lon, relative_alt, n, e, time.perf_counter()
        ):
            return None
        return GlobalPosition(t, lat, lon, relative_alt, n, e)

    def _note_origin(self, lat: float, lon: float, alt: float) -> None:
        """GPS_GLOBAL_ORIGIN: the local frame's origin. Taken only before the alignment is
        set: a jump of the offset in flight would move every commanded point."""
        self._origin = (lat, lon, alt)
        if self.alignment is not None and not self.alignment.ready:
            self.alignment.from_global_origin(lat, lon, alt)

    @property
    def home(self) -> tuple[float, float] | None:
        """The vehicle's home (lat, lon) from its latest HOME_POSITION, if one came."""
        return None if self._home is None else self._home[:2]

    def _note_home(self, lat: float, lon: float, alt: float, x: float, y: float) -> None:
        self._home = (lat, lon, alt, x, y)

    def _vehicle_xy(self, north: float, east: float) -> tuple[float, float]:
        """A profile-frame point in the vehicle's local frame (position setpoints)."""
        a = self.alignment
        return (north, east) if a is None else a.to_vehicle(north, east)

    async def read_origin(self, wait: float = 3.0) -> tuple[float, float, float] | None:
        """Where the vehicle's local frame starts (lat, lon, alt AMSL) when it is flown in that
        frame (a profile without ``site``: the run map draws its path there): its
        GPS_GLOBAL_ORIGIN, asked once with REQUEST_MESSAGE; None when it sends none (the
        emulator refuses the request: its frame is the profile's)."""
        if self._origin is None:
            asked = await self.command_long(
                mavlink2.MAV_CMD_REQUEST_MESSAGE, float(mavlink2.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN)
            )
            if asked.outcome is Outcome.ACCEPTED:
                deadline = time.monotonic() + wait
                while self._origin is None and time.monotonic() < deadline:
                    await asyncio.sleep(0.05)
        return self._origin

    async def learn_origin(self, wait: float = 3.0) -> str | None:
        """Ask for GPS_GLOBAL_ORIGIN (the local frame's origin); without one within ``wait``
        wall s, use HOME_POSITION (home in WGS84 and in the local frame). Returns None once
        aligned, else what was missing (call again)."""
        a = self.alignment
        if a is None or a.ready:
            return None
        origin = await self.command_long(
            mavlink2.MAV_CMD_REQUEST_MESSAGE, float(mavlink2.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN)
        )
        await self.command_long(
            mavlink2.MAV_CMD_REQUEST_MESSAGE, float(mavlink2.MAVLINK_MSG_ID_HOME_POSITION)
        )
        # A vehicle that refused the request (the emulator) sends no origin: do not wait for it.
        deadline = time.monotonic() + (wait if origin.outcome is Outcome.ACCEPTED else 0.2)
        while not a.ready and time.monotonic() < deadline:
            await asyncio.sleep(0.05)
        if not a.ready and self._home is not None:
            a.from_home(*self._home)
        if a.ready:
            return None
        return "neither GPS_GLOBAL_ORIGIN nor HOME_POSITION (asked with REQUEST_MESSAGE)"

    # -- the vehicle's own fence -------------------------------------------------------------

    async def upload_fence(self, vertices: list[tuple[int, int]]) -> None:
        """Replace the vehicle's fence with this inclusion polygon ((lat, lon) in 1e-7 deg);
        raises FenceTransferError saying at which step it failed."""
        raise FenceTransferError(f"the {type(self).__name__} backend does not upload fences")

    async def download_fence(self) -> list[tuple[int, int]]:
        """The inclusion-polygon vertices the vehicle stores."""
        raise FenceTransferError(f"the {type(self).__name__} backend does not read fences")

    # -- the autopilot's own log -------------------------------------------------------------

    async def download_log(self, stem: Path, limit: float) -> FlightLog:
        """The autopilot's newest log (the flight just flown) into ``stem`` + its format's
        suffix, within ``limit`` wall s; where it cannot be had, why (log_transfer.py)."""
        return FlightLog(None, note=f"the {type(self).__name__} backend does not download logs")

    # -- the vehicle's words ---------------------------------------------------------------

    def _note_text(self, severity: int, text: str) -> None:
        self._texts.append((time.monotonic(), severity, text))

    async def _with_reason(self, result: CommandResult, since: float) -> CommandResult:
        """A refusal with the vehicle's STATUSTEXT (warning or worse) sent since ``since``."""
        if result.outcome is Outcome.ACCEPTED or result.reason:
            return result
        deadline = time.monotonic() + _REASON_WAIT_S
        while True:
            texts = [
                t for w, s, t in self._texts if w >= since and s <= mavlink2.MAV_SEVERITY_WARNING
            ]
            if texts or time.monotonic() >= deadline:
                break
            await asyncio.sleep(0.05)
        if not texts:
            return result
        return CommandResult(result.what, result.outcome, result.result, "; ".join(texts[-2:]))

    @abstractmethod
    async def _set_sensor(self, index: int) -> CommandResult:
        """PARAM_SET MDM_SENSOR, confirmed by its echo."""

    async def __aenter__(self) -> VehicleLink:
        await self.open()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()
