"""The geofence on Python floats gives the array form's answers, result for result."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from companion.geofence import Geofence

_SHAPES = [
    np.array([[0.0, 0.0], [20000.0, 0.0], [20000.0, 20000.0], [0.0, 20000.0]]),
    np.array([[0.0, 0.0], [1000.0, 0.0], [1000.0, 1000.0], [0.0, 600.0]]),
    np.array([[0.0, 0.0], [400.0, -300.0], [900.0, 100.0], [500.0, 250.0], [600.0, 800.0]]),
]


def _reference_nearest(v: np.ndarray, point: np.ndarray) -> tuple[float, np.ndarray]:
    """The array form the fence used before (np.roll / einsum / norm / argmin)."""
    b = np.roll(v, -1, axis=0)
    ab = b - v
    t = np.clip(np.einsum("kd,kd->k", point - v, ab) / np.einsum("kd,kd->k", ab, ab), 0, 1)
    nearest = v + t[:, None] * ab
    d = np.linalg.norm(nearest - point, axis=1)
    i = int(np.argmin(d))
    return float(d[i]), nearest[i]


def _reference_contains(v: np.ndarray, point: np.ndarray) -> bool:
    if _reference_nearest(v, point)[0] <= 1e-9:
        return True
    x, y = float(point[0]), float(point[1])
    inside = False
    for a, b in zip(v, np.roll(v, -1, axis=0), strict=True):
        if (a[1] > y) != (b[1] > y):
            cross = a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
            if x < cross:
                inside = not inside
    return inside


@settings(max_examples=500, deadline=None)
@given(st.sampled_from(range(len(_SHAPES))), st.floats(-30000, 30000), st.floats(-30000, 30000))
def test_contains_and_clamp_match_the_array_form(shape: int, n: float, e: float) -> None:
    v = _SHAPES[shape]
    fence = Geofence(v)
    p = np.array([n, e])
    inside = _reference_contains(v, p)
    assert fence.contains(p) == inside
    expected = p if inside else _reference_nearest(v, p)[1]
    assert np.array_equal(fence.clamp(p), expected)


def test_vertices_and_edge_midpoints_are_inside() -> None:
    for v in _SHAPES:
        fence = Geofence(v)
        for p in np.concatenate([v, (v + np.roll(v, -1, axis=0)) / 2]):
            assert fence.contains(p)
            assert np.array_equal(fence.clamp(p), p)
