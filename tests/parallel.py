"""How the suite shares this machine under pytest-xdist (`-n 3 --dist loadgroup`, README
"Tests"): the SITL tests run in two lanes, a whole module to one lane, each lane on one worker
with SITL instance indices of its own; the Docker tests in one group (one worker builds the
images once); every other test goes to whichever worker is free.

A lane is a pytest-xdist group: its tests run one after another on one worker, so at most two
SITL flights share the cores at a time. Modules are dealt to the lanes longest first, by the
seconds they took in the last measured run (README "Tests", the durations table); a module not
measured yet counts DEFAULT_S per test."""

from __future__ import annotations

from collections.abc import Iterable

SITL_LANES = 2
LANE_WIDTH = 4
"""SITL instance indices per lane: a team of four (instance indices stop at 9, PX4's)."""
DOCKER_SITL_BASE = 2 * LANE_WIDTH
"""The first instance index of the Docker tests that fly SITL (two instances: 8 and 9)."""
DEFAULT_S = 120.0

MEASURED_S: dict[str, float] = {
    "tests/ground/test_fleet_sitl_team.py": 635.0,
    "tests/companion/test_sitl_flights.py": 559.0,
    "tests/companion/test_autopilot_failsafes_sitl.py": 250.0,
    "tests/companion/test_battery_reserve_sitl.py": 221.0,
    "tests/companion/test_kill_failsafe_sitl.py": 203.0,
    "tests/companion/test_flight_log_sitl.py": 171.0,
    "tests/sim_vehicle_stub/test_svs_plan_differential.py": 162.0,
    "tests/ground/live_web/test_sitl_team_page.py": 161.0,
    "tests/companion/test_serial_link_sitl.py": 155.0,
    "tests/ground/test_fleet_file_sitl.py": 147.0,
    "tests/sim_vehicle_stub/test_svs_differential.py": 123.0,
    "tests/companion/test_wind_gps_sitl.py": 123.0,
    "tests/companion/test_sensor_sources_sitl.py": 111.0,
    "tests/companion/test_lying_link_sitl.py": 66.0,
    "tests/companion/test_plan_fence_sitl.py": 62.0,
    "tests/sim_vehicle_stub/test_svs_mission_plugin_differential.py": 61.0,
    "tests/companion/test_field_mission_sitl.py": 53.0,
    "tests/mavlink_conformance/test_conformance_sitl.py": 52.0,
    "tests/sim_vehicle_stub/test_svs_mission_differential.py": 51.0,
    "tests/ground/test_run_map_own_origin.py": 36.0,
    "tests/companion/test_safety_net_check_sitl.py": 25.0,
    "tests/companion/test_fence_transfer_sitl.py": 3.0,
}
"""Wall seconds per SITL module in the last measured run (a full CI rehearsal on 2026-12-03 beside
other work, load 5-18; the battery reserve and flight-log modules as measured after their cuts)."""


def sitl_lanes(tests_per_module: dict[str, int]) -> dict[str, int]:
    """Each SITL module's lane: longest first, to the lane with the least so far."""
    cost = {m: MEASURED_S.get(m, DEFAULT_S * n) for m, n in tests_per_module.items()}
    load = [0.0] * SITL_LANES
    lanes: dict[str, int] = {}
    for module in sorted(cost, key=lambda m: (-cost[m], m)):
        lane = min(range(SITL_LANES), key=lambda k: (load[k], k))
        lanes[module] = lane
        load[lane] += cost[module]
    return lanes


def group_of(markers: Iterable[str], module: str, lanes: dict[str, int]) -> str | None:
    """The xdist group of a test with ``markers`` in ``module`` (None: any worker)."""
    found = set(markers)
    if "docker" in found:
        return "docker"
    if "sitl" in found:
        return f"sitl-{lanes[module]}"
    return None


def instance_base(group: str | None) -> int | None:
    """The first SITL instance index of a test in ``group`` (None: not a SITL group)."""
    if group == "docker":
        return DOCKER_SITL_BASE
    if group is not None and group.startswith("sitl-"):
        return int(group.removeprefix("sitl-")) * LANE_WIDTH
    return None
