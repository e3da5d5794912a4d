"""Virtual sensors: the same targets as the emulator (same seed) and a confirmation on the
emulator whose own sensors stay off (the companion never switches them on)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from companion.sensors.virtual_source import VirtualSensorSource
from companion.telemetry import events, read_log, read_records
from mdm_ground.fleet.runner import FleetOptions, run_fleet
from mdm_profiles import builtin_profile, load_profile
from sim_vehicle_stub.config import EmulatorConfig
from sim_vehicle_stub.emulator import Emulator
from tests.emulator_harness import free_udp_base
from tests.profile_files import levels, sensors, write_profile_with


@pytest.mark.parametrize("name", ["paper-dynamic-false", "paper-popup-false"])
def test_virtual_targets_are_the_emulators_for_the_same_seed(name: str) -> None:
    profile = builtin_profile(name)
    emulator = Emulator(EmulatorConfig(profile=profile, seed=7, bind_port_base=0))
    virtual = VirtualSensorSource(profile, seed=7)
    other = VirtualSensorSource(profile, seed=8)
    for t in (0.0, 55.5, 400.0, 1234.5):
        assert np.array_equal(virtual.targets_at(t), emulator.sensors.targets_at(t))
    if profile.target_motion is not None:
        assert not np.array_equal(other.targets_at(400.0), virtual.targets_at(400.0))


def test_virtual_confirmation_sees_false_targets_only_with_the_detection_sensor() -> None:
    profile = builtin_profile("paper-fixed-false")
    source = VirtualSensorSource(profile, seed=1)
    false = next(t for t in profile.targets if t.false_target)
    source.select(0, 0.0)
    source.observe(1.0, false.north + 10.0, false.east)
    assert [tuple(p) for p in source.take()] == [(false.north, false.east)]
    source.select(len(profile.sensors) - 1, 2.0)
    source.observe(3.0, false.north + 10.0, false.east)
    assert len(source.take()) == 0
    assert source.signal < np.exp(-1.0)  # no real target within the confirmation radius


@pytest.mark.usefixtures("fleet_processes")
@pytest.mark.timeout(150)
def test_virtual_sensors_confirm_the_real_target_with_the_emulators_sensors_off(
    tmp_path: Path,
) -> None:
    path = write_profile_with(
        tmp_path / "profile.yaml",
        "virtual-sensor-test",
        area={"north": 2000.0, "east": 2000.0},
        targets=[
            {"north": 1000.0, "east": 1000.0},
            {"north": 600.0, "east": 1400.0, "false_target": True},
        ],
        fleet={"vehicles": 1, "start": "periphery_even"},
        sensors=sensors(1500.0, 60.0),
        sensor_source={"kind": "virtual"},
        policy={"levels": levels(500.0, 300.0, 400.0)},
        mission={"duration": 3000.0, "ts_cap": 3000.0},
    )
    out = tmp_path / "run"
    result = run_fleet(
        FleetOptions(
            profile=str(path),
            out=out,
            speedup=50.0,
            duration=3000.0,
            base_port=free_udp_base(1),
            seed=3,
            wall_limit=120,
        )
    )
    logged = read_log(out / "mission-0.jsonl")
    confirmations = logged.of(events.Confirmation)
    assert confirmations, f"no confirmation; ended {result.end_reasons}"
    assert [e.reason for e in logged.of(events.End)] == ["all targets"]
    target = load_profile(path).targets[0]
    gap = np.hypot(confirmations[0].north - target.north, confirmations[0].east - target.east)
    assert gap < 1e-6, f"confirmed {gap:.1f} m from the real target"
    assert result.tnc == 1
    assert result.false_confirmations == 0
    emulator = read_records(out / "emulator-events.jsonl")
    sensing = [r for r in emulator if r["event"] in ("entered_range", "detected", "confirmed")]
    assert sensing == [], "the emulator's own sensors read targets (it was asked to switch them on)"
    assert any(r["event"] == "target_appeared" for r in emulator)  # its log was written
