"""The SITL lanes and groups of tests/parallel.py: balanced, whole modules, apart indices."""

from __future__ import annotations

import pytest

from tests import parallel


def test_modules_are_dealt_longest_first_to_the_emptier_lane() -> None:
    lanes = parallel.sitl_lanes({"a.py": 1, "b.py": 1, "c.py": 1, "d.py": 3})
    # d: 360 s, the rest 120 s each: d alone in one lane, a, b, c in the other
    assert lanes["d.py"] != lanes["a.py"]
    assert lanes["a.py"] == lanes["b.py"] == lanes["c.py"]


def test_the_measured_seconds_count_before_the_default() -> None:
    teams = "tests/ground/test_fleet_sitl_team.py"
    lanes = parallel.sitl_lanes({teams: 1, "x.py": 4, "y.py": 1})
    assert lanes[teams] != lanes["x.py"]  # 600 s measured against 480 s by default


def test_groups_keep_docker_together_and_give_each_lane_its_own_indices() -> None:
    lanes = {"m.py": 1}
    assert parallel.group_of({"docker", "sitl"}, "m.py", lanes) == "docker"
    assert parallel.group_of({"sitl", "broker"}, "m.py", lanes) == "sitl-1"
    assert parallel.group_of({"broker", "fleet"}, "m.py", lanes) is None
    bases = [parallel.instance_base(f"sitl-{k}") for k in range(parallel.SITL_LANES)]
    bases.append(parallel.instance_base("docker"))
    assert bases == [0, 4, 8]
    assert parallel.instance_base(None) is None


@pytest.mark.parametrize("group", ["sitl-0", "sitl-1"])
def test_a_lanes_team_of_four_stays_below_the_last_px4_index(group: str) -> None:
    base = parallel.instance_base(group)
    assert base is not None
    assert base + parallel.LANE_WIDTH - 1 < parallel.DOCKER_SITL_BASE <= 9
