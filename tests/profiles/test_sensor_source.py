"""The profile's sensor_source section: default, choices, bounds, and the error that names them."""

from __future__ import annotations

import pytest

from mdm_profiles import ProfileError, builtin_profile
from mdm_profiles.overrides import apply_overrides


def test_paper_profiles_read_the_vehicles_mavlink_readings() -> None:
    assert builtin_profile("paper-fixed").sensor_source.kind == "mavlink"


def test_a_kind_outside_the_three_is_refused_naming_them() -> None:
    with pytest.raises(ProfileError) as err:
        apply_overrides(builtin_profile("paper-fixed"), ["sensor_source.kind=camera"])
    assert "sensor_source.kind" in str(err.value)
    assert "'mavlink', 'virtual' or 'mqtt'" in str(err.value)


@pytest.mark.parametrize(
    "setting", ["sensor_source.silence_timeout=0", "sensor_source.min_confidence=1.5"]
)
def test_out_of_range_settings_are_refused(setting: str) -> None:
    with pytest.raises(ProfileError, match=setting.split("=", maxsplit=1)[0]):
        apply_overrides(builtin_profile("paper-fixed"), [setting])
