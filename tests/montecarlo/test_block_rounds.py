"""The compiled round loop leaves and resumes a block whenever a dynamic target's path must grow:
the block's outcome must not depend on when the paths are drawn."""

from __future__ import annotations

import numpy as np
import pytest

from mdm_core.world import Scenario, TargetTracks
from mdm_montecarlo.engines import engine
from mdm_montecarlo.kernels.compiled_tracks import compiled_tracks
from mdm_profiles import builtin_profile


def test_paths_drawn_as_needed_give_the_same_block_as_paths_drawn_first(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    profile = builtin_profile("paper-dynamic")
    growths: list[int] = []

    def counted(
        scenario: Scenario, n_runs: int, rng: np.random.Generator, horizon: float
    ) -> TargetTracks:
        tracks = compiled_tracks(scenario, n_runs, rng, horizon)
        segments = tracks.segments

        def grow(until: float) -> tuple[np.ndarray, np.ndarray]:
            before = tracks.filled
            out = segments(until)
            growths.append(tracks.filled - before)
            return out

        monkeypatch.setattr(tracks, "segments", grow)
        return tracks

    monkeypatch.setattr(engine, "shared_tracks", counted)
    lazy = engine.run_block(profile, 5, 0, 40)
    # Not vacuous: the loop came back for more path many times, mid-block.
    assert sum(g > 0 for g in growths) >= 3

    def drawn_first(
        scenario: Scenario, n_runs: int, rng: np.random.Generator, horizon: float
    ) -> TargetTracks:
        tracks = compiled_tracks(scenario, n_runs, rng, horizon)
        tracks.segments(horizon)
        return tracks

    monkeypatch.setattr(engine, "shared_tracks", drawn_first)
    eager = engine.run_block(profile, 5, 0, 40)
    np.testing.assert_array_equal(lazy.per_vehicle, eager.per_vehicle)
    assert lazy.events == eager.events
    assert np.isfinite(lazy.per_vehicle).sum() > 100
