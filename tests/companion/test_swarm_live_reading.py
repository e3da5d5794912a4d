"""The live companion flies only the interval swarm that forgets confirmed targets: a profile
with the engine's defaults (one iteration per waypoint, kept memory) is refused by name."""

from __future__ import annotations

from companion.mission.swarm_core import live_swarm_refusal
from mdm_montecarlo.study.variants import with_method
from mdm_profiles import builtin_profile


def test_the_waypoint_defaults_are_refused_naming_each_setting() -> None:
    refusal = live_swarm_refusal(with_method(builtin_profile("paper-fixed"), "PSO"))
    assert refusal is not None
    for setting in ("iteration", "after_confirmation", "read_confirmed"):
        assert f"policy.swarm.{setting}" in refusal
    assert "swarm-small.yaml" in refusal


def test_the_live_swarm_profile_is_flown() -> None:
    assert live_swarm_refusal(builtin_profile("swarm-small")) is None
