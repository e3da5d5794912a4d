"""The lawnmower teams' flights, compiled (numba): every lane of a block, leg after leg.

A lane flies its plan (mdm_core.search.lawnmower: the transit to its cell, then the sweep back
and forth) in straight legs at the fleet speed; a leg's sensor-disc entries are the closed
form of ``entry_kernel.entry_row``, piece by piece between a moving target's path nodes.

One sensor (``two_sensor`` False, LM1): the confirmation sensor is on all the time; a lane
confirms every real target whose disc it enters and keeps its course.

Two sensors (LM2): on the lanes the detection sensor is on (one sensor at a time, as MDM's
level 1). The first detection of a target the vehicle has not confirmed (and has not searched
for in vain within ``hold`` s; ``hold`` < 0: in this pass over the cell) starts the confirmation search: the spiral's offsets
(lawnmower.spiral), rotated to the heading at detection, around the point of detection, with
the confirmation sensor on, until the detected target is confirmed or the spiral ends (a
target confirmed on the way counts too). Then the vehicle flies back to the point on its lane
where it left it (detection sensor on; a detection on the way starts another search, and the
vehicle still goes back to the same point) and goes on.

Lanes do not talk, so each is flown alone to the end; a lane stops at the cap, or past the
mission duration once its run has confirmed every real target (later confirmations change
neither T_nc nor T_S). ``first`` holds each lane's first confirmation of each target up to
then. Nothing is random: the results depend only on the targets and start points (the
block's streams), so are the same for any number of workers.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mdm_core.jit import compiled
from mdm_montecarlo.kernels.entry_kernel import entry_row

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

SWEEP, SEARCH, RETURN = range(3)
ARRIVED = 1e-9
"""Metres from a waypoint at which it counts as reached."""


@compiled
def fly_lawnmower(
    two_sensor: bool,
    waypoints: FloatArray,
    start: FloatArray,
    n_vehicles: int,
    speed: float,
    duration: float,
    cap: float,
    area: FloatArray,
    spiral: FloatArray,
    hold: float,
    detect_radius: float,
    confirm_radius: float,
    appear: FloatArray,
    real: BoolArray,
    seg_start: FloatArray,
    seg_velocity: FloatArray,
    grid_dt: float,
    moving: bool,
    top_speed: float,
    first: FloatArray,
) -> tuple[int, float]:
    """Fly every lane (``waypoints`` (lanes, K, 2) its sweep, ``start`` (lanes, 2) its start
    point; lane = run * n_vehicles + vehicle), writing ``first`` (lanes, targets) in place
    (inf: not confirmed). Returns the legs flown and the vehicle-seconds simulated."""
    n, count, _ = waypoints.shape
    runs = n // n_vehicles
    m = appear.shape[0]
    team = np.full((runs, m), np.inf)
    eligible = np.zeros((1, m), dtype=np.bool_)
    out = np.empty(m)
    resolved = np.zeros(m, dtype=np.bool_)
    hold_until = np.zeros(m)
    legs = 0
    simulated = 0.0
    for lane in range(n):
        r = lane // n_vehicles
        row = r if moving else 0
        for j in range(m):
            resolved[j] = False
            hold_until[j] = 0.0
        x = start[lane, 0]
        y = start[lane, 1]
        t = 0.0
        mode = SWEEP
        k = 0
        step = 1
        s = 0
        sought = 0
        cx = cy = hx = hy = 0.0
        back_x = back_y = 0.0
        while t < cap:
            if t >= duration:
                done = True
                for j in range(m):
                    if real[j] and team[r, j] > t:
                        done = False
                        break
                if done:
                    break
            if mode == SWEEP:
                px = waypoints[lane, k, 0]
                py = waypoints[lane, k, 1]
            elif mode == RETURN:
                px = back_x
                py = back_y
            else:
                ox = spiral[s, 0]
                oy = spiral[s, 1]
                px = min(max(cx + ox * hx - oy * hy, 0.0), area[0])
                py = min(max(cy + ox * hy + oy * hx, 0.0), area[1])
            dx = px - x
            dy = py - y
            dist = math.sqrt(dx * dx + dy * dy)
            arrive = dist <= ARRIVED
            if not arrive:
                vx = dx / dist * speed
                vy = dy / dist * speed
                full = dist / speed
                leg = min(full, cap - t)
                confirming = not two_sensor or mode == SEARCH
                if confirming:
                    radius = confirm_radius
                    for j in range(m):
                        eligible[0, j] = real[j] and first[lane, j] == np.inf
                else:
                    radius = detect_radius
                    for j in range(m):
                        eligible[0, j] = not resolved[j] and hold_until[j] <= t
                        if hold_until[j] > t:
                            leg = min(leg, hold_until[j] - t)
                entry_row(
                    x,
                    y,
                    vx,
                    vy,
                    leg,
                    t,
                    row,
                    radius,
                    eligible,
                    0,
                    appear,
                    seg_start,
                    seg_velocity,
                    grid_dt,
                    top_speed,
                    moving,
                    out,
                )
                legs += 1
                if confirming:
                    # Every contact of the first piece with any (a moving target's later
                    # pieces are solved from the last of them on), in a search only those up
                    # to the sought target's.
                    latest = -1.0
                    until = np.inf  # the search ends at the sought target's confirmation
                    if mode == SEARCH:
                        until = out[sought]
                    for j in range(m):
                        if out[j] <= until and out[j] != np.inf:
                            first[lane, j] = t + out[j]
                            team[r, j] = min(team[r, j], t + out[j])
                            resolved[j] = True
                            latest = max(latest, out[j])
                    if latest >= 0.0:
                        x += vx * latest
                        y += vy * latest
                        t += latest
                        if mode == SEARCH and resolved[sought]:
                            mode = RETURN
                        continue
                else:
                    soonest = np.inf
                    found = -1
                    for j in range(m):
                        if out[j] < soonest:
                            soonest = out[j]
                            found = j
                    if found >= 0:
                        x += vx * soonest
                        y += vy * soonest
                        t += soonest
                        if mode == SWEEP:
                            back_x = x
                            back_y = y
                        mode = SEARCH
                        sought = found
                        s = 0
                        cx = x
                        cy = y
                        hx = vx / speed
                        hy = vy / speed
                        continue
                if leg < full:  # stopped short: the cap or a hold ending
                    x += vx * leg
                    y += vy * leg
                    t += leg
                    continue
                x = px
                y = py
                t += leg
            # Arrived at the waypoint.
            if mode == SWEEP:
                k += step
                if k == count or k < 0:
                    step = -step
                    k += 2 * step
                    for j in range(m):  # a new pass: the targets held for one pass count again
                        if hold_until[j] == np.inf:
                            hold_until[j] = 0.0
            elif mode == RETURN:
                mode = SWEEP
            else:
                s += 1
                if s == spiral.shape[0]:
                    hold_until[sought] = t + hold if hold >= 0.0 else np.inf
                    mode = RETURN
        simulated += t
    return legs, simulated
