"""The lawnmower plan (mdm_core.search.lawnmower): its cells tile the area, one per vehicle,
its lanes cover every point of a cell, and the cells go to the start points of least transit."""

from __future__ import annotations

import itertools

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from mdm_core.search import lawnmower

sizes = st.tuples(st.floats(100.0, 30000.0), st.floats(100.0, 30000.0))


def _starts(size: tuple[float, float], n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.asarray(rng.uniform(0.0, 1.0, (n, 2)) * np.asarray(size))


def _distance_to_path(points: np.ndarray, path: np.ndarray) -> np.ndarray:
    """Distance of each point (p, 2) to the polyline ``path`` (k, 2)."""
    a = path[:-1][None]
    d = (path[1:] - path[:-1])[None]
    rel = points[:, None] - a
    length2 = np.maximum((d * d).sum(-1), 1e-12)
    s = np.clip((rel * d).sum(-1) / length2, 0.0, 1.0)
    return np.asarray(np.linalg.norm(rel - s[..., None] * d, axis=-1).min(axis=1))


@settings(max_examples=60, deadline=None)
@given(
    size=sizes,
    n=st.integers(1, 30),
    radius=st.floats(20.0, 3000.0),
    overlap=st.sampled_from([0.0, 0.1, 0.5]),
    seed=st.integers(0, 2**31),
)
def test_cells_tile_the_area_and_lanes_cover_each(
    size: tuple[float, float], n: int, radius: float, overlap: float, seed: int
) -> None:
    spacing = lawnmower.lane_spacing(radius, overlap)
    plan = lawnmower.plan(size, _starts(size, n, seed), spacing)
    assert plan.regions.shape == (n, 2, 2)
    area = size[0] * size[1]
    extents = plan.regions[:, 1] - plan.regions[:, 0]
    np.testing.assert_allclose(extents.prod(-1), area / n, rtol=1e-9)  # equal areas
    points = np.random.default_rng(seed + 1).uniform(0.0, 1.0, (400, 2)) * np.asarray(size)
    inside = np.all(
        (points[:, None] >= plan.regions[None, :, 0])
        & (points[:, None] < plan.regions[None, :, 1]),
        axis=-1,
    )
    # Disjoint and complete: every point of the area in exactly one cell.
    assert (inside.sum(axis=1) == 1).all()
    owner = inside.argmax(axis=1)
    for i in range(n):
        mine = points[owner == i]
        if len(mine):
            # Within the sensor's reach (half the spacing) of the owner's own sweep.
            gaps = _distance_to_path(mine, plan.waypoints[i])
            assert gaps.max() <= spacing / 2 * (1 + 1e-9) + 1e-6
        # The sweep stays inside its cell.
        assert (plan.waypoints[i] >= plan.regions[i, 0] - 1e-9).all()
        assert (plan.waypoints[i] <= plan.regions[i, 1] + 1e-9).all()


@settings(max_examples=40, deadline=None)
@given(size=sizes, n=st.integers(1, 6), seed=st.integers(0, 2**31))
def test_assignment_is_the_least_total_transit(
    size: tuple[float, float], n: int, seed: int
) -> None:
    starts = _starts(size, n, seed)
    grid = lawnmower.choose_grid(size, n, 400.0)
    boxes = lawnmower.cells(grid)
    order, corner = lawnmower.assign(boxes, starts)
    assert sorted(order.tolist()) == list(range(n))  # one cell per vehicle
    near = np.linalg.norm(lawnmower.corners(boxes)[None] - starts[:, None, None], axis=-1).min(-1)
    best = min(sum(near[v, c] for v, c in enumerate(p)) for p in itertools.permutations(range(n)))
    chosen = lawnmower.corners(boxes)[order, corner]
    assert np.linalg.norm(chosen - starts, axis=-1).sum() <= best + 1e-6
    plan = lawnmower.plan(size, starts, 400.0)
    # Each starts at that corner: its first lane half a lane gap across from it.
    half_gap = grid.cell[1 - grid.axis] / grid.lanes / 2
    np.testing.assert_allclose(np.linalg.norm(plan.waypoints[:, 0] - chosen, axis=-1), half_gap)


def test_grid_is_the_shortest_sweep_paper_area() -> None:
    """20 km square, 12 vehicles, 800 m lanes: 12 strips of 1667 m would need 3 lanes each
    (60 km); the 4 x 3 grid of 5 x 6.67 km cells sweeps 9 lanes of 5 km (about 50 km)."""
    grid = lawnmower.choose_grid((20000.0, 20000.0), 12, 800.0)
    assert grid.sweep_length < 52000.0
    assert grid.rows * grid.cols == 12
    strips = lawnmower.Grid(12, 1, 1, 3, (20000.0 / 12, 20000.0))
    assert grid.sweep_length < strips.sweep_length


@settings(max_examples=40, deadline=None)
@given(
    detect=st.floats(100.0, 5000.0),
    share=st.floats(0.05, 0.5),
    chords=st.integers(8, 64),
    inward=st.booleans(),
    seed=st.integers(0, 2**31),
)
def test_spiral_covers_the_detection_disc(
    detect: float, share: float, chords: int, inward: bool, seed: int
) -> None:
    """Every point of the detection disc (r1) is within r2 of the confirmation search (less the
    chords' sagitta), the rim included: where a fixed target detected on entry lies."""
    confirm = detect * share
    path = lawnmower.spiral(detect, 2 * confirm, chords, inward)
    assert np.linalg.norm(path, axis=-1).max() <= detect
    rng = np.random.default_rng(seed)
    angle = rng.uniform(0, 2 * np.pi, 500)
    rho = detect * np.sqrt(rng.uniform(0, 1, 500))
    rho[:100] = detect  # on the rim
    points = np.stack([rho * np.cos(angle), rho * np.sin(angle)], -1)
    sagitta = detect * (1 - np.cos(np.pi / chords))
    assert _distance_to_path(points, path).max() <= confirm + sagitta + 1e-6
