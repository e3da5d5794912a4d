"""12 companions + the emulator on the paper's fixed scenario, sped up: real confirmations only.

The full matrix (both backends x both personas) is marked slow: `pytest -m slow tests/companion`.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from mdm_ground.fleet.runner import FleetOptions, run_fleet
from mdm_profiles import load_profile

pytestmark = pytest.mark.usefixtures("fleet_processes")

MATRIX = [
    pytest.param("pymavlink", "px4", id="pymavlink-px4"),
    pytest.param("mavsdk", "ardupilot", id="mavsdk-ardupilot", marks=pytest.mark.slow),
    pytest.param("pymavlink", "ardupilot", id="pymavlink-ardupilot", marks=pytest.mark.slow),
    pytest.param("mavsdk", "px4", id="mavsdk-px4", marks=pytest.mark.slow),
]


@pytest.mark.timeout(300)
@pytest.mark.parametrize(("backend", "persona"), MATRIX)
def test_twelve_companions_confirm_only_real_targets(
    tmp_path: Path, backend: str, persona: str
) -> None:
    profile = load_profile("paper-fixed-false")
    result = run_fleet(
        FleetOptions(
            profile="paper-fixed-false",
            out=tmp_path,
            speedup=100.0,
            duration=600.0,
            backend=backend,
            persona=persona,
            seed=2,
            wall_limit=240,
        )
    )
    assert result.complete, result.ends
    assert result.end_reasons == dict.fromkeys(range(12), "mission time")
    assert result.confirmations, "no target confirmed in 600 sim s by 12 vehicles"
    radius = profile.sensors[-1].radius
    for c in result.confirmations:
        assert not profile.targets[c.target].false_target, f"false target confirmed: {c}"
        assert c.distance <= radius, f"confirmation {c.distance:.0f} m from any target: {c}"
    assert result.false_confirmations == 0
