"""The fleet's flight checks from mission logs: a vehicle that searched outside its altitude layer
is named in the summary, and each vehicle's share of search time near the fence is counted
from its search ticks only."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from mdm_ground.fleet.flight_checks import flight_checks
from mdm_ground.fleet.scoring import score
from mdm_ground.fleet.summary import summary_lines
from mdm_profiles import load_profile

PROFILE = load_profile("field-duebendorf")  # layers 40, 45, 50, 55 m; fence 40-60 m inside


def _log(out: Path, vehicle: int, ticks: list[tuple[str, float, float, float]]) -> None:
    records: list[dict[str, Any]] = [
        {"t": 10.0 * k, "event": "tick", "phase": phase, "north": n, "east": e, "alt": alt}
        for k, (phase, n, e, alt) in enumerate(ticks)
    ]
    (out / f"mission-{vehicle}.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))


def test_a_vehicle_off_its_layer_is_named_and_fence_time_counts_search_ticks_only(
    tmp_path: Path,
) -> None:
    middle = (600.0, 1000.0)
    by_fence = (600.0, 70.0)  # the fence runs about 50 m east of the area's west edge
    _log(
        tmp_path,
        0,
        [
            ("climb", *by_fence, 20.0),
            ("search", *middle, 40.0),
            ("search", *by_fence, 40.5),
            ("search", *middle, 39.0),
        ],
    )
    _log(
        tmp_path,
        1,
        [("search", *middle, 45.0), ("search", *middle, 48.0), ("return", *by_fence, 48.0)],
    )
    checks = flight_checks(PROFILE, tmp_path, 2)
    assert [c.samples for c in checks] == [3, 2]
    assert checks[0].near_fence == 1 / 3  # the climbing tick by the fence does not count
    assert checks[0].outside_layer == 0
    assert checks[0].problem() is None
    assert checks[1].near_fence == 0.0
    assert checks[1].outside_layer == 1
    result = score(PROFILE, tmp_path, 2, 900.0)
    result.flight_checks, result.complete = checks, True
    lines = summary_lines(result, tmp_path, 1.0)
    assert "  search time within 30 m of the fence, per vehicle: 0: 33%, 1: 0%" in lines
    assert (
        "  LAYER: vehicle 1 left its altitude layer 45 m: 1 of 2 search samples more than "
        "2 m off (worst 48.0 m)"
    ) in lines


def test_results_hold_each_vehicles_safety_net_before_and_after(tmp_path: Path) -> None:
    net = {
        "mode": "set",
        "state": "ok",
        "rate": 1.0,
        "params": [{"name": "GF_ACTION", "before": 2.0, "after": 3.0, "needed": "3"}],
    }
    _log(tmp_path, 0, [("search", 600.0, 1000.0, 40.0)])
    with (tmp_path / "mission-0.jsonl").open("a") as f:
        f.write(json.dumps({"t": 1.0, "event": "safety_net", **net}) + "\n")
    _log(tmp_path, 1, [("search", 600.0, 1000.0, 45.0)])  # a restarted companion: none
    result = score(PROFILE, tmp_path, 2, 900.0)
    assert result.safety_net == {0: net}
    assert result.as_json()["safety_net"] == {0: net}
