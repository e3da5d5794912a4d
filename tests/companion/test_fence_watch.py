"""The field fence: moved inwards for the guidance, the start check and the breach check on the
GPS position, with distance and direction in words."""

from __future__ import annotations

import numpy as np
import pytest

from companion.fence_from_profile import (
    fence_for,
    fence_watch,
    guidance_fence,
    profile_frame,
    site_geometry,
)
from companion.geofence import Geofence
from companion.mission.fence_watch import compass
from mdm_profiles import load_profile


@pytest.mark.parametrize("reverse", [False, True], ids=["as-given", "reversed"])
def test_inset_moves_every_edge_inwards_by_the_margin(reverse: bool) -> None:
    fence = fence_for(load_profile("field-duebendorf"))
    if reverse:
        fence = Geofence(fence.vertices[::-1])
    inner = fence.inset(20.0)
    for vertex in inner.vertices:
        assert fence.contains(vertex)
        assert fence.distance(*vertex) == pytest.approx(20.0, abs=1e-6)
    middle_of_edges = (inner.vertices + np.roll(inner.vertices, -1, axis=0)) / 2
    for point in middle_of_edges:
        assert fence.distance(*point) == pytest.approx(20.0, abs=1e-6)


def test_inset_larger_than_the_fence_is_a_clear_error() -> None:
    with pytest.raises(ValueError, match="too small"):
        Geofence.rectangle(30.0, 30.0).inset(20.0)


def test_guidance_fence_is_the_inset_site_fence_and_paper_profiles_keep_the_area() -> None:
    field = load_profile("field-duebendorf")
    assert field.site is not None
    inner = guidance_fence(field)
    assert np.allclose(inner.vertices, fence_for(field).inset(field.site.fence_inset).vertices)
    paper = load_profile("paper-fixed")
    assert np.array_equal(guidance_fence(paper).vertices, fence_for(paper).vertices)
    assert fence_watch(paper) is None


def test_site_geometry_builds_one_fence_that_the_guidance_and_the_watch_share() -> None:
    field = load_profile("field-duebendorf")
    assert field.site is not None
    site = site_geometry(field)
    assert site.frame == profile_frame(field)
    assert np.array_equal(site.fence.vertices, fence_for(field).vertices)
    assert np.allclose(site.guidance.vertices, site.fence.inset(field.site.fence_inset).vertices)
    assert site.watch is not None
    assert site.watch.fence is site.fence  # the watch checks the fence built here, not another
    paper = site_geometry(load_profile("paper-fixed"))
    assert paper.guidance is paper.fence
    assert paper.watch is None


def test_start_refused_beyond_the_margin_with_distance_and_direction() -> None:
    watch = fence_watch(load_profile("field-duebendorf"))
    assert watch is not None
    assert watch.start_refusal(600.0, 1000.0) is None  # inside
    assert watch.start_refusal(-90.0, 1000.0) is None  # 90 m south: within the 100 m margin
    assert watch.start_refusal(-3000.0, 1000.0) == (
        "3000 m south of the search area (allowed: 100 m outside it)"
    )
    diagonal = watch.start_refusal(1200.0 + 300.0, 2000.0 + 400.0)
    assert diagonal is not None
    assert diagonal.startswith("500 m north-east")


def test_breach_only_outside_the_fence_itself() -> None:
    watch = fence_watch(load_profile("field-duebendorf"))
    assert watch is not None
    assert watch.breach(600.0, 1000.0) is None
    assert watch.breach(1170.0, 1000.0) == "10.0 m north of the fence"  # fence edge ~1160 m N


@pytest.mark.parametrize(
    ("dn", "de", "word"),
    [(1, 0, "north"), (1, 1, "north-east"), (0, 1, "east"), (-1, 0, "south"), (-1, -1, "south-west"),
     (0, -1, "west"), (1, -1, "north-west")],
)  # fmt: skip
def test_compass_words(dn: float, de: float, word: str) -> None:
    assert compass(dn, de) == word
