"""The partitioned lawnmower (boustrophedon) baseline: a plan fixed before take-off, no talk.

The area is cut into one equal-area cell per vehicle (a grid of rows x cols = vehicles), each
cell swept in straight lanes along one axis, lanes ``spacing`` apart at most (2 r of the
sensor that sweeps, less the overlap), joined by turns along the cell's edge. Which vehicle
sweeps which cell is the assignment of cells to start points of least total transit (each
vehicle to the nearest corner of its cell); a vehicle starts its cell at that corner. When the
last lane is done the vehicle sweeps the cell again in reverse (pop-up and moving targets can
appear in swept ground), back and forth until the mission ends. docs/model.md, "The
lawnmower baseline", gives every choice and its measured effect.

The grid (rows, cols, lane axis) is the one of least path per vehicle for one sweep: lanes x
lane length + turns; ties go to the squarer cell. It depends on the area, the team size and
the spacing only, so every run of a profile has the same cells; the start points pick who
flies which.

Pure: no clocks, sockets or files; the engine, the companion and the planner call it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


@dataclass(frozen=True)
class Grid:
    """How the area is cut: ``rows`` x ``cols`` cells (rows along north), lanes along ``axis``
    (0 north, 1 east), ``lanes`` per cell."""

    rows: int
    cols: int
    axis: int
    lanes: int
    cell: tuple[float, float]
    """A cell's extent (north, east), metres."""

    @property
    def sweep_length(self) -> float:
        """Metres flown in one sweep of a cell: its lanes and the turns between them."""
        along = self.cell[self.axis]
        across = self.cell[1 - self.axis]
        return self.lanes * along + (self.lanes - 1) * across / self.lanes


def lanes_across(width: float, spacing: float) -> int:
    """Lanes that cover ``width`` metres at most ``spacing`` apart (each lane covers half the
    spacing on either side)."""
    return max(1, math.ceil(width / spacing - 1e-9))


def choose_grid(size: tuple[float, float], vehicles: int, spacing: float) -> Grid:
    """The grid of least path per vehicle for one sweep (ties: the squarer cell)."""
    if vehicles < 1:
        raise ValueError(f"a lawnmower plan needs at least one vehicle, got {vehicles}")
    if not spacing > 0:
        raise ValueError(f"lane spacing must be > 0 m, got {spacing}")
    best: tuple[float, float, Grid] | None = None
    for rows in range(1, vehicles + 1):
        if vehicles % rows:
            continue
        cols = vehicles // rows
        cell = (size[0] / rows, size[1] / cols)
        for axis in (0, 1):
            grid = Grid(rows, cols, axis, lanes_across(cell[1 - axis], spacing), cell)
            key = (round(grid.sweep_length, 6), abs(math.log(cell[0] / cell[1])))
            if best is None or key < best[:2]:
                best = (*key, grid)
    assert best is not None
    return best[2]


def cells(grid: Grid) -> FloatArray:
    """Every cell's (low corner, high corner), (vehicles, 2, 2), row by row."""
    out = np.empty((grid.rows * grid.cols, 2, 2))
    for r in range(grid.rows):
        for c in range(grid.cols):
            k = r * grid.cols + c
            out[k, 0] = (r * grid.cell[0], c * grid.cell[1])
            out[k, 1] = ((r + 1) * grid.cell[0], (c + 1) * grid.cell[1])
    return out


def corners(boxes: FloatArray) -> FloatArray:
    """The four corners (cells, 4, 2) of cells (cells, 2, 2): (lo, lo), (lo, hi), (hi, lo),
    (hi, hi) in (north, east)."""
    lo, hi = boxes[:, 0], boxes[:, 1]
    return np.stack(
        [
            np.stack([lo[:, 0], lo[:, 1]], -1),
            np.stack([lo[:, 0], hi[:, 1]], -1),
            np.stack([hi[:, 0], lo[:, 1]], -1),
            np.stack([hi[:, 0], hi[:, 1]], -1),
        ],
        axis=1,
    )


def assign(boxes: FloatArray, starts: FloatArray) -> tuple[IntArray, IntArray]:
    """Which cell each start point (vehicles, 2) sweeps, and from which of its corners: the
    assignment of least total distance from each start to the nearest corner of its cell."""
    # Imported here: scipy.optimize loads scipy.special, which the Monte-Carlo CLI keeps out
    # of its start-up until the workers have started (tests/montecarlo/test_cli.py).
    from scipy.optimize import linear_sum_assignment

    gaps = np.linalg.norm(corners(boxes)[None, :, :, :] - starts[:, None, None, :], axis=-1)
    nearest = gaps.min(axis=-1)  # (vehicles, cells)
    vehicle, cell = linear_sum_assignment(nearest)
    order = np.empty(len(starts), dtype=np.intp)
    order[vehicle] = cell
    corner = np.argmin(gaps[np.arange(len(starts)), order], axis=-1)
    return order, corner.astype(np.intp)


def sweep(box: FloatArray, corner: int, grid: Grid) -> FloatArray:
    """The waypoints (2 lanes, 2) of one sweep of cell ``box`` (2, 2) from ``corner``: each lane
    from one edge of the cell to the other along ``grid.axis``, lanes evenly spread across it
    (half a gap from each side), alternating direction."""
    axis = grid.axis
    other = 1 - axis
    lo, hi = box[0], box[1]
    point = corners(box[None])[0, corner]
    width = hi[other] - lo[other]
    gap = width / grid.lanes
    cross = lo[other] + (np.arange(grid.lanes) + 0.5) * gap
    if point[other] > lo[other]:  # the corner is on the high side: lanes from there down
        cross = cross[::-1]
    ends = (lo[axis], hi[axis]) if point[axis] == lo[axis] else (hi[axis], lo[axis])
    out = np.empty((2 * grid.lanes, 2))
    for k, c in enumerate(cross):
        a, b = ends if k % 2 == 0 else ends[::-1]
        out[2 * k, axis], out[2 * k, other] = a, c
        out[2 * k + 1, axis], out[2 * k + 1, other] = b, c
    return out


@dataclass(frozen=True)
class Plan:
    """A team's lawnmower plan: vehicle i sweeps ``regions[i]`` along ``waypoints[i]``."""

    grid: Grid
    regions: FloatArray
    """(vehicles, 2, 2) each vehicle's cell, low and high corners."""
    waypoints: FloatArray
    """(vehicles, 2 lanes, 2) one sweep of each vehicle's cell, in flying order."""


def plan(size: tuple[float, float], starts: FloatArray, spacing: float) -> Plan:
    """The plan of a team starting at ``starts`` (vehicles, 2) over an area of ``size``
    (north, east) with lanes at most ``spacing`` apart."""
    grid = choose_grid(size, len(starts), spacing)
    boxes = cells(grid)
    order, corner = assign(boxes, starts)
    regions = boxes[order]
    waypoints = np.stack([sweep(regions[i], int(corner[i]), grid) for i in range(len(starts))])
    return Plan(grid, regions, waypoints)


def lane_spacing(radius: float, overlap: float) -> float:
    """Lane spacing for a sensor of ``radius``: 2 r, less the ``overlap`` share (0 <= o < 1)."""
    if not 0.0 <= overlap < 1.0:
        raise ValueError(f"lane overlap must be in [0, 1), got {overlap}")
    return 2.0 * radius * (1.0 - overlap)


def spiral(radius: float, spacing: float, chords_per_turn: int, inward: bool) -> FloatArray:
    """The confirmation search of a two-sensor lawnmower (offsets (points, 2) from the point
    of detection, starting straight ahead, +north; the flier rotates them to its heading):
    a full circle of radius ``radius - spacing / 4``, then an Archimedean spiral from it to the
    centre whose turns are ``spacing`` (2 r2) apart, in chords of 1 / ``chords_per_turn`` turn;
    ``inward`` False flies the same path from the centre out. The circle passes half a
    confirmation radius inside the detection disc's rim, where a fixed target detected on
    entering the disc lies: a ring at r1 - r2 would pass it at exactly r2, its chords outside
    r2, never confirming it; and a spiral alone is at its outer radius only where it starts."""
    outer = max(radius - spacing / 4.0, 0.0)
    turns = outer / spacing
    count = max(1, math.ceil(turns * chords_per_turn))
    theta = np.linspace(0.0, 2.0 * math.pi * turns, count + 1)
    rho = outer - spacing * theta / (2.0 * math.pi)
    rho[-1] = 0.0
    ring = np.linspace(0.0, 2.0 * math.pi, chords_per_turn + 1)
    circle = np.stack([outer * np.cos(ring), outer * np.sin(ring)], axis=-1)
    inner = np.stack([rho * np.cos(theta), rho * np.sin(theta)], axis=-1)
    points = np.concatenate([circle[:-1], inner])
    return np.asarray(points if inward else points[::-1].copy())
