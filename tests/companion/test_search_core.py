"""The live adapter steps the shared SearchPolicy like the batch engine does."""

from __future__ import annotations

import numpy as np

from companion.mission.search_core import SearchCore
from mdm_profiles import load_profile


def test_detection_raises_level_and_confirmation_is_remembered_once() -> None:
    core = SearchCore(load_profile("paper-fixed"), seed=3, vehicle=0)
    core.start(np.array([0.0, 0.0]), 0.0, memory=[])
    assert core.level == 0
    assert core.sensor() == 0
    d = core.step(1.0, np.array([10.0, 10.0]), False, np.array([[1500.0, 900.0]]))
    assert d.detected
    assert d.level == 1
    assert core.sensor() == 1
    two_readings = np.array([[1990.0, 2001.0], [2003.0, 1998.0]])
    d = core.step(2.0, np.array([1800.0, 1800.0]), False, two_readings)
    assert len(d.confirmed) == 1
    assert core.level == 0
    assert core.confirmed_count == 1
    d = core.step(3.0, np.array([1800.0, 1800.0]), False, np.array([[2000.0, 2000.0]]))
    assert not d.detected
    assert d.confirmed == []


def test_restarted_core_ignores_targets_confirmed_before() -> None:
    core = SearchCore(load_profile("paper-fixed"), seed=3, vehicle=0)
    core.start(np.array([0.0, 0.0]), 50.0, memory=[(2000.0, 2000.0)])
    d = core.step(51.0, np.array([1900.0, 1900.0]), False, np.array([[2010.0, 1990.0]]))
    assert not d.detected
    assert core.level == 0


def test_no_step_needed_without_news() -> None:
    core = SearchCore(load_profile("paper-fixed"), seed=3, vehicle=0)
    core.start(np.array([0.0, 0.0]), 0.0, memory=[])
    here = np.array([0.0, 0.0])
    assert not core.needs_step(10.0, here, False, np.zeros((0, 2)))
    assert core.needs_step(10.0, here, True, np.zeros((0, 2)))
