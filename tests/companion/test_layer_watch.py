"""The altitude layer read back live (companion/mission/layer_watch.py): a vehicle that stays off
its layer during the search is reported at once, on the console and as a typed mission-log
event, and again when it is back; a single stray position is not."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from companion.mission import MissionConfig
from companion.mission.layer_watch import LAYER_HOLD_S, LAYER_TOLERANCE_M, LayerWatch
from companion.telemetry import events
from companion.telemetry.mission_log import MissionLog, read_log
from mdm_profiles import load_profile


class _Mission:
    """The two things the watch needs of a VehicleMission: its config and its durable log."""

    def __init__(self, config: MissionConfig) -> None:
        self.config = config
        self.log = MissionLog(config.mission_log_path())
        self.t = 0.0

    def record(self, event: events.DurableEvent) -> None:
        self.log.emit(self.t, event.NAME, **events.to_fields(event))


def _fly(watch: LayerWatch, mission: _Mission, altitudes: list[tuple[float, float]]) -> None:
    for t, alt in altitudes:
        mission.t = t
        watch.check(t, alt)


def test_a_vehicle_off_its_layer_is_reported_live_and_again_when_back(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    profile = load_profile("field-duebendorf")
    mission = _Mission(MissionConfig(vehicle=2, profile=profile, log_dir=tmp_path))
    layer = profile.fleet.altitude + 2 * profile.fleet.altitude_step
    watch = LayerWatch(mission)
    low = layer - LAYER_TOLERANCE_M - 3.0
    steps = [i * 0.1 for i in range(200)]
    track = [(t, layer + 0.5) for t in steps[:50]]  # in its layer
    track += [(t, low) for t in steps[50:120]]  # 7 s well below it: a neighbour's layer
    track += [(t, layer) for t in steps[120:]]  # back
    with caplog.at_level(logging.WARNING, logger="companion.mission.layer_watch"):
        _fly(watch, mission, track)
    mission.log.close()
    logged = [(e.t, e.event) for e in read_log(mission.config.mission_log_path()).events]
    assert [e for _, e in logged] == [
        events.AltitudeLayer("outside", round(low, 1), layer, LAYER_TOLERANCE_M),
        events.AltitudeLayer("back", layer, layer, LAYER_TOLERANCE_M),
    ]
    # reported once the state held LAYER_HOLD_S, not at the end of the run
    assert logged[0][0] == pytest.approx(5.0 + LAYER_HOLD_S)
    assert logged[1][0] == pytest.approx(12.0 + LAYER_HOLD_S)
    lines = [r.getMessage() for r in caplog.records]
    assert lines[0] == (
        f"vehicle 2 outside its altitude layer: {low:.1f} m above home, "
        f"layer {layer:g} m (+-{LAYER_TOLERANCE_M:g} m)"
    )
    assert lines[1].startswith(f"vehicle 2 back in its altitude layer {layer:g} m")


def test_a_short_excursion_or_jitter_inside_the_tolerance_is_not_reported(tmp_path: Path) -> None:
    profile = load_profile("field-duebendorf")
    mission = _Mission(MissionConfig(vehicle=0, profile=profile, log_dir=tmp_path))
    layer = profile.fleet.altitude
    watch = LayerWatch(mission)
    track = [(i * 0.1, layer + (LAYER_TOLERANCE_M - 0.1) * (-1) ** i) for i in range(100)]
    track += [(10.0 + i * 0.1, layer + 10.0) for i in range(int(LAYER_HOLD_S * 10) - 2)]
    track += [(12.0 + i * 0.1, layer) for i in range(100)]
    _fly(watch, mission, track)
    mission.log.close()
    assert read_log(mission.config.mission_log_path()).events == []
    assert not watch.outside
