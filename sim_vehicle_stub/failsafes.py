"""Failsafe checks run every telemetry tick: setpoint loss, link loss, geofence, battery.

Each fires once per occurrence and re-arms when its condition clears. Time-outs are sim seconds.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mdm_core.world import Area
from sim_vehicle_stub.personas.base import Action, Behaviour
from sim_vehicle_stub.vehicle import Vehicle

FloatArray = NDArray[np.float64]

_IDLE_DRAIN = 0.1
"""Battery drain on the ground while armed, as a fraction of the flying drain."""


def check_failsafes(vehicle: Vehicle, inside_fence: bool, dt: float) -> None:
    """Run every failsafe of ``vehicle`` after ``dt`` sim seconds since the last check;
    ``inside_fence`` says whether it is within the search area plus its MDM_FENCE_MARG."""
    _battery(vehicle, dt)
    if not vehicle.armed:
        return
    _setpoint_loss(vehicle)
    _link_loss(vehicle)
    _geofence(vehicle, inside_fence)


def inside_fences(area: Area, positions: FloatArray, margins: list[float]) -> list[bool]:
    """For every vehicle (n, 2), whether it is inside the area grown by its margin: in plain
    floats (for a dozen vehicles numpy's cost per call was most of the time)."""
    north, east = area.north, area.east
    return [
        -m <= n <= north + m and -m <= e <= east + m
        for (n, e), m in zip(positions.tolist(), margins, strict=True)
    ]


def _setpoint_loss(v: Vehicle) -> None:
    if v.mode.behaviour is not Behaviour.EXTERNAL or v.setpoint is None or v.setpoint_lost:
        return
    timeout, action = v.limits.setpoint
    if v.now - v.setpoint.t <= timeout:
        return
    if not v.persona.position_targets_time_out and v.setpoint.velocity is None:
        return  # ArduPilot keeps flying to a position target without a stream
    v.setpoint_lost = True
    if v.persona.position_targets_time_out:
        v.failsafe(action, "setpoint loss")
    else:
        # ArduPilot: the vehicle stops and holds, staying in GUIDED.
        v.fleet.hold(v.index)
        v.say(4, "Guided: velocity target timed out, stopping")
        v.events.write(v.now, "failsafe", vehicle=v.index, cause="setpoint loss", action="stop")


def _link_loss(v: Vehicle) -> None:
    if v.last_gcs_heartbeat is None:
        return  # no link was ever established
    timeout, action = v.limits.link
    lost = v.now - v.last_gcs_heartbeat > timeout
    if lost and not v.link_lost and action is not Action.NONE:
        v.link_lost = True
        v.failsafe(action, "link loss")
    elif not lost:
        v.link_lost = False


def _geofence(v: Vehicle, inside: bool) -> None:
    if inside:
        v.fence_breached = False
        return
    action = v.limits.fence
    if not v.fence_breached and not v.landed and action is not Action.NONE:
        v.fence_breached = True
        v.failsafe(action, "geofence")


def _battery(v: Vehicle, dt: float) -> None:
    if not v.armed:
        return
    drain = dt / v.limits.endurance
    v.battery = max(0.0, v.battery - (_IDLE_DRAIN * drain if v.landed else drain))
    threshold, action = v.limits.battery
    if not v.battery_fired and v.battery < threshold and action is not Action.NONE:
        v.battery_fired = True
        if v.mode.behaviour not in (Behaviour.RTL, Behaviour.LAND):
            v.failsafe(action, "low battery")
