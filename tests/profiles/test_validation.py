"""Mission profile validation: every problem names the file, the field and what is allowed."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest
import yaml

from mdm_profiles import (
    MissionProfile,
    ProfileError,
    builtin_profile,
    builtin_profiles,
    load_profile,
    write_profile,
)
from mdm_profiles.overrides import apply_overrides

REPO = Path(__file__).resolve().parents[2]
SHIPPED = sorted((REPO / "mission_profiles").glob("*.yaml"))


def _paper_fixed() -> dict[str, Any]:
    data = yaml.safe_load((REPO / "mission_profiles" / "paper-fixed.yaml").read_text())
    assert isinstance(data, dict)
    return data


def _error(tmp_path: Path, data: Any, name: str = "bad.yaml") -> tuple[str, str]:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data) if not isinstance(data, str) else data)
    with pytest.raises(ProfileError) as info:
        load_profile(path)
    return str(info.value), str(path)


def _broken(edit: Any) -> dict[str, Any]:
    data = copy.deepcopy(_paper_fixed())
    edit(data)
    return data


def test_every_builtin_profile_loads() -> None:
    names = builtin_profiles()
    assert len(names) >= 6
    for name in names:
        profile = builtin_profile(name)
        assert isinstance(profile, MissionProfile)
        assert profile.name == name


@pytest.mark.parametrize("path", SHIPPED, ids=[p.stem for p in SHIPPED])
def test_every_repository_profile_loads_by_path_and_by_name(path: Path) -> None:
    assert load_profile(path) == load_profile(path.stem)


def test_unknown_top_level_key_is_named_with_the_allowed_keys(tmp_path: Path) -> None:
    text, path = _error(tmp_path, _broken(lambda d: d.update(duratoin=5)))
    assert path in text
    assert f"{path}: duratoin: unknown key" in text
    assert "allowed: name, description, area, origin, targets" in text


def test_unknown_nested_key_is_named_by_its_dotted_path(tmp_path: Path) -> None:
    text, path = _error(tmp_path, _broken(lambda d: d["policy"]["levels"][1]["index"].update(k=1)))
    assert f"{path}: policy.levels.1.index.k: unknown key" in text
    assert "allowed: gamma, index_max, index_min, kappa" in text


def test_wrong_type_names_the_field_and_the_value(tmp_path: Path) -> None:
    text, path = _error(tmp_path, _broken(lambda d: d["fleet"].update(vehicles="twelve")))
    assert f"{path}: fleet.vehicles:" in text
    assert "valid integer" in text
    assert "'twelve'" in text


def test_unknown_distribution_lists_ls_bs_and_us(tmp_path: Path) -> None:
    text, path = _error(
        tmp_path, _broken(lambda d: d["policy"]["levels"][0].update(distribution="XS"))
    )
    assert f"{path}: policy.levels.0.distribution:" in text
    assert "'LS', 'BS' or 'US'" in text
    assert "'XS'" in text


def test_negative_sensor_radius_names_the_sensor_and_the_bound(tmp_path: Path) -> None:
    text, path = _error(tmp_path, _broken(lambda d: d["sensors"][1].update(radius=-400.0)))
    assert f"{path}: sensors.1.radius:" in text
    assert "greater than 0" in text
    assert "-400" in text


def test_levels_and_sensors_count_mismatch_names_both(tmp_path: Path) -> None:
    text, path = _error(tmp_path, _broken(lambda d: d["sensors"].pop()))
    assert path in text
    assert "policy.kind 'mdm' needs one level per sensor: 2 levels, 1 sensors" in text


def test_single_sensor_policy_with_two_levels_is_rejected(tmp_path: Path) -> None:
    text, _ = _error(tmp_path, _broken(lambda d: d["policy"].update(kind="sss")))
    assert "'sss' takes exactly one level" in text


def test_index_on_level_1_is_rejected(tmp_path: Path) -> None:
    index = {"gamma": 0.1, "index_max": 0.95, "index_min": 0.2, "kappa": 150.0}
    text, _ = _error(tmp_path, _broken(lambda d: d["policy"]["levels"][0].update(index=index)))
    assert "policy.levels[0] (level 1) takes no index" in text


def test_level_2_without_index_is_rejected(tmp_path: Path) -> None:
    text, _ = _error(tmp_path, _broken(lambda d: d["policy"]["levels"][1].pop("index")))
    assert "policy.levels[1] needs an index" in text


def test_out_of_order_decay_index_names_the_level(tmp_path: Path) -> None:
    text, path = _error(
        tmp_path, _broken(lambda d: d["policy"]["levels"][1]["index"].update(gamma=0.5))
    )
    assert f"{path}: policy.levels.1.index:" in text
    assert "0 < gamma < index_min < index_max" in text


def test_sensors_out_of_radius_order_are_rejected(tmp_path: Path) -> None:
    text, _ = _error(tmp_path, _broken(lambda d: d["sensors"].reverse()))
    assert "decreasing radius, got [400.0, 2000.0]" in text


def test_target_outside_the_area_is_rejected(tmp_path: Path) -> None:
    text, _ = _error(tmp_path, _broken(lambda d: d["targets"][0].update(north=20001.0)))
    assert "target at (20001.0, 2000.0) lies outside the area" in text


def test_profile_of_false_targets_only_is_rejected(tmp_path: Path) -> None:
    def all_false(d: dict[str, Any]) -> None:
        for t in d["targets"]:
            t["false_target"] = True

    text, _ = _error(tmp_path, _broken(all_false))
    assert "at least one target must be real" in text


def test_bad_walk_boundary_lists_the_allowed_rules(tmp_path: Path) -> None:
    text, path = _error(tmp_path, _broken(lambda d: d.update(target_motion={"boundary": "wrap"})))
    assert f"{path}: target_motion.boundary:" in text
    assert "'reflect', 'clamp', 'bounce' or 'free'" in text


def test_missing_required_field_is_named(tmp_path: Path) -> None:
    text, path = _error(tmp_path, _broken(lambda d: d.pop("policy")))
    assert f"{path}: policy: Field required" in text


def test_every_problem_is_listed(tmp_path: Path) -> None:
    def two(d: dict[str, Any]) -> None:
        d["fleet"]["speed"] = 0
        d["mission"]["duration"] = -1

    text, path = _error(tmp_path, _broken(two))
    assert "(2 problem(s))" in text
    assert f"{path}: fleet.speed:" in text
    assert f"{path}: mission.duration:" in text


def test_invalid_yaml_names_the_file(tmp_path: Path) -> None:
    text, path = _error(tmp_path, "name: [unclosed\n")
    assert text.startswith(f"{path}: not valid YAML")


def test_invalid_yaml_quotes_the_line_and_points_at_the_column(tmp_path: Path) -> None:
    # libyaml's own messages give only "line 2, column 8"; the message quotes the line.
    text, _ = _error(tmp_path, "name: x\nfleet: {vehicles: 3: 4}\n")
    assert text.endswith("line 2, column 20:\n    fleet: {vehicles: 3: 4}\n" + " " * 23 + "^")


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_shipped_profiles_read_the_same_with_either_yaml_parser(path: Path) -> None:
    text = path.read_text()
    assert load_profile(path) == MissionProfile.model_validate(yaml.safe_load(text))


def test_yaml_that_is_not_a_mapping_is_rejected(tmp_path: Path) -> None:
    text, path = _error(tmp_path, "- a\n- b\n")
    assert text == f"{path}: a profile is a YAML mapping, got list"


def test_missing_file_lists_the_builtin_profiles(tmp_path: Path) -> None:
    missing = tmp_path / "nope.yaml"
    with pytest.raises(ProfileError) as info:
        load_profile(missing)
    assert str(missing) in str(info.value)
    assert "paper-fixed" in str(info.value)


def test_unknown_builtin_name_lists_the_builtin_profiles() -> None:
    with pytest.raises(ProfileError, match="paper-popup"):
        builtin_profile("paper-nothing")


@pytest.mark.parametrize("name", builtin_profiles())
def test_a_written_profile_loads_back_equal(name: str, tmp_path: Path) -> None:
    changed = apply_overrides(builtin_profile(name), ["mission.duration=123.0"])
    write_profile(changed, tmp_path / "p.yaml")
    again = load_profile(tmp_path / "p.yaml")
    assert again == changed
    assert again.mission.duration == 123.0
