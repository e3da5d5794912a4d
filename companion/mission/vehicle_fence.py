"""The profile's fence as the vehicle's own: uploaded (mission protocol, mission_type FENCE),
read back and compared, and switched on once the vehicle is inside it, so the autopilot keeps
the vehicle in even if the companion dies."""

from __future__ import annotations

import logging
from collections.abc import Callable

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.geofence import Geofence
from companion.link.base import LinkError, VehicleLink
from companion.link.fence_protocol import FenceTransferError

log = logging.getLogger(__name__)


class VehicleFence:
    """One vehicle's copy of the site fence; ``emit`` writes ``vehicle_fence`` events."""

    def __init__(
        self,
        link: VehicleLink,
        polygon: list[tuple[float, float]],
        vehicle: int,
        emit: Callable[..., None],
    ) -> None:
        self.link = link
        self.polygon = polygon
        self.vertices = [(round(lat * 1e7), round(lon * 1e7)) for lat, lon in polygon]
        self.vehicle = vehicle
        self.emit = emit
        self.installed = False
        """Uploaded, read back equal, its fence type set: ready to switch on."""
        self.enabling = False
        self.settled = False
        """:meth:`install` is over, whatever its outcome (the safety net waits for it: both
        write the fence type)."""

    async def install(self) -> None:
        """Upload, read back, compare; set the fence type. Says why where it cannot. Where
        the autopilot enforces any fence it holds (PX4), the upload waits for :meth:`enable`."""
        try:
            await self._install()
        finally:
            self.settled = True

    def home_inside(self) -> bool:
        """The vehicle's home (its latest HOME_POSITION) is inside the fence."""
        home = self.link.home
        # Containment is the same ray casting on (lat, lon) degrees as on metres.
        return home is not None and Geofence(np.array(self.polygon)).contains(home)

    async def _install(self) -> None:
        ap = self.link.autopilot
        params = ap.fence_params if ap is not None else None
        if params is None or not self.link.uploads_fence:
            why = (
                f"not done for {ap.name if ap else 'an unknown autopilot'}"
                if params is None
                else f"the {type(self.link).__name__} backend has no fence upload"
            )
            log.info(
                "vehicle %d: own fence %s; the companion's fence watch still applies",
                self.vehicle,
                why,
            )
            self.emit("vehicle_fence", state="skipped", reason=why)
            return
        if params.enable is None:
            home = self.link.home
            if home is not None and not self.home_inside():
                why = (
                    f"home {home[0]:.6f}, {home[1]:.6f} is outside the fence: the "
                    "autopilot would stop the RTL at the fence"
                )
                log.warning("vehicle %d: own fence not uploaded: %s", self.vehicle, why)
                self.emit("vehicle_fence", state="skipped", reason=why)
                return
            log.info(
                "vehicle %d: own fence uploaded once the vehicle is inside it "
                "(the autopilot enforces any fence it holds)",
                self.vehicle,
            )
            self.installed = True
            return
        if not await self._upload():
            return
        assert params.kind is not None
        kind = await self.link.read_param(params.kind)
        if kind is None:
            self.emit("vehicle_fence", state="failed", reason=f"{params.kind} not readable")
            return
        wanted = (int(kind) | params.polygon_bit) & ~params.drop_bits
        if wanted != int(kind):
            echoed = await self.link.set_param(
                params.kind, float(wanted), mavlink2.MAV_PARAM_TYPE_INT8
            )
            if echoed is None or int(echoed) != wanted:
                self.emit(
                    "vehicle_fence",
                    state="failed",
                    reason=f"{params.kind} {int(kind)} -> {wanted} not confirmed",
                )
                return
        log.info(
            "vehicle %d: own fence uploaded, %d vertices read back equal; %s %d -> %d",
            self.vehicle,
            len(self.vertices),
            params.kind,
            int(kind),
            wanted,
        )
        self.emit(
            "vehicle_fence",
            state="uploaded",
            vertices=len(self.vertices),
            read_back="equal",
            fence_type=[int(kind), wanted],
        )
        self.installed = True

    async def _upload(self) -> bool:
        """Upload and read back; False (an event says why) unless the vehicle holds it."""
        try:
            await self.link.upload_fence(self.vertices)
            back = await self.link.download_fence()
        except (FenceTransferError, LinkError) as exc:
            log.warning("vehicle %d: own fence not installed: %s", self.vehicle, exc)
            self.emit("vehicle_fence", state="failed", reason=str(exc))
            return False
        if back != self.vertices:
            log.error(
                "vehicle %d: fence read back differs: sent %s, vehicle has %s",
                self.vehicle,
                self.vertices,
                back,
            )
            self.emit("vehicle_fence", state="mismatch", sent=self.vertices, read=back)
            return False
        return True

    async def enable(self) -> None:
        """Switch the fence on (once; the vehicle is inside it now): its enable parameter, or
        where there is none (PX4) the upload itself."""
        ap = self.link.autopilot
        if self.enabling or ap is None or ap.fence_params is None:
            return
        self.enabling = True
        params = ap.fence_params
        if params.enable is None:
            if not await self._upload():
                return
            action = await self.link.read_param(params.action) if params.action else None
            shown = "unknown" if action is None else f"{action:g}"
            log.info(
                "vehicle %d: own fence uploaded inside it, %d vertices read back equal; %s %s",
                self.vehicle,
                len(self.vertices),
                params.action,
                shown,
            )
            self.emit(
                "vehicle_fence", state="uploaded", vertices=len(self.vertices), read_back="equal"
            )
            self.emit("vehicle_fence", state="enabled", param=params.action, value=action)
            return
        name = params.enable
        echoed = await self.link.set_param(name, 1.0, mavlink2.MAV_PARAM_TYPE_INT8)
        if echoed is None or int(echoed) != 1:
            log.warning("vehicle %d: %s=1 not confirmed (%s)", self.vehicle, name, echoed)
            self.emit("vehicle_fence", state="failed", reason=f"{name}=1 not confirmed")
            return
        log.info("vehicle %d: own fence on (%s=1)", self.vehicle, name)
        self.emit("vehicle_fence", state="enabled", param=name)
