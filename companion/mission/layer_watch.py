"""The altitude layer read back live: in a team that does not talk, each vehicle's altitude
layer (fleet.altitude + i x altitude_step, Assumption III) is the only separation from the
others, so during the search every position the vehicle reports is checked against it, and a
vehicle that stays off its layer is reported at once (a console line and an ``altitude_layer``
record), and again when it is back, not only in the fleet's summary after the run."""

from __future__ import annotations

import logging
from typing import Protocol

from companion.mission.config import MissionConfig
from companion.telemetry import events

log = logging.getLogger(__name__)

LAYER_TOLERANCE_M = 2.0
"""A vehicle is in its layer within this many metres of it; with the profiles' 5 m steps, under
half the distance to a neighbour's layer."""
LAYER_HOLD_S = 2.0
"""Vehicle seconds a vehicle must stay off (or back in) its layer before that is reported: a
single position of a gust or a GPS jump is not a lost separation."""


class Watched(Protocol):
    """What the watch reads of the mission and asks of it (VehicleMission)."""

    @property
    def config(self) -> MissionConfig: ...
    def record(self, event: events.DurableEvent) -> None: ...


class LayerWatch:
    """Checks each search position's altitude (m above home) against the vehicle's layer."""

    def __init__(self, mission: Watched) -> None:
        self.m = mission
        self.outside = False
        """The state last reported: off the layer."""
        self._since: float | None = None
        """Vehicle time the altitude began to differ from the state reported."""

    def check(self, t: float, altitude: float) -> None:
        """One position at vehicle time ``t``: report a change of state that lasted
        LAYER_HOLD_S."""
        layer = self.m.config.altitude
        off = abs(altitude - layer) > LAYER_TOLERANCE_M
        if off == self.outside:
            self._since = None
            return
        if self._since is None:
            self._since = t
        if t - self._since < LAYER_HOLD_S:
            return
        self.outside, self._since = off, None
        state = "outside" if off else "back"
        v = self.m.config.vehicle
        if off:
            log.warning(
                "vehicle %d outside its altitude layer: %.1f m above home, layer %g m (+-%g m)",
                v,
                altitude,
                layer,
                LAYER_TOLERANCE_M,
            )
        else:
            log.warning("vehicle %d back in its altitude layer %g m (%.1f m)", v, layer, altitude)
        self.m.record(events.AltitudeLayer(state, round(altitude, 1), layer, LAYER_TOLERANCE_M))
