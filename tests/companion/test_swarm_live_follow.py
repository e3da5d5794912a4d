"""Live PSO: a vehicle's signal pulls the others towards the target, through MQTT.

Three companions and the emulator share their bests through the Mosquitto on 127.0.0.1:1883.
Vehicle 0 starts inside the signal radius of the only real target (seed 11 puts it 859 m away,
the signal reaches 900 m); the other two start about 2 km away and only hear of it. The same
fleet (same seed: same start positions, same exploration draws) is flown again with every
message lost (message_drop 1.0).

The runs' clocks are not comparable (companions start a few seconds apart, differently in each
run), so everything is measured on events: each iteration that follows a peer's best logs a
``swarm_follow`` event (own position, the best's position), and times are taken from the
vehicle's own search start (its first ``level`` event).
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from companion.mission.swarm_core import LIVE_READING
from companion.telemetry import read_records
from mdm_ground.fleet.runner import FleetOptions, run_fleet
from tests.profile_files import sensors, write_profile_with

pytestmark = pytest.mark.usefixtures("fleet_processes", "mqtt_broker")

VEHICLES = 3
TARGET = (600.0, 1900.0)
SIGNAL_RADIUS = 900.0
Log = list[dict[str, Any]]


def _fly(tmp_path: Path, drop: float) -> list[Log]:
    prefix = f"mdm/test-{os.getpid()}-swarm-follow-{drop}"
    swarm = {
        **LIVE_READING,
        "signal_radius": SIGNAL_RADIUS,
        "update_interval": 2.0,
        "message_drop": drop,
    }
    profile = write_profile_with(
        tmp_path / f"profile-{drop}.yaml",
        "swarm-live-follow-test",
        area={"north": 2500.0, "east": 2500.0},
        targets=[
            {"north": TARGET[0], "east": TARGET[1]},
            {"north": 2200.0, "east": 300.0, "false_target": True},
        ],
        fleet={"vehicles": VEHICLES},
        sensors=sensors(1000.0, 100.0),
        policy={"kind": "pso", "levels": [{"distribution": "US", "step": 2500.0}], "swarm": swarm},
        mission={"duration": 200.0, "ts_cap": 200.0},
        mqtt={"host": "127.0.0.1", "port": 1883, "topic_prefix": prefix},
    )
    out = tmp_path / f"run-{drop}"
    run_fleet(
        FleetOptions(
            profile=str(profile), out=out, speedup=50.0, duration=200.0, seed=11, wall_limit=60
        )
    )
    return [list(read_records(out / f"mission-{i}.jsonl")) for i in range(VEHICLES)]


def _start(log: Log) -> float:
    """Vehicle time at which the search started (the first level event)."""
    return float(next(r["t"] for r in log if r["event"] == "level"))


def _follows(log: Log) -> Log:
    return [r for r in log if r["event"] == "swarm_follow"]


def _distance_at(log: Log, since_start: float) -> float:
    """Distance to the target ``since_start`` seconds after the vehicle's search start,
    interpolated between the positions of its 10 s ticks."""
    t0 = _start(log)
    ticks = [r for r in log if r["event"] == "tick"]
    return float(
        np.interp(
            since_start,
            [r["t"] - t0 for r in ticks],
            [math.dist((r["north"], r["east"]), TARGET) for r in ticks],
        )
    )


@pytest.mark.timeout(120)
def test_a_peers_signal_pulls_the_others_towards_the_target(tmp_path: Path) -> None:
    shared = _fly(tmp_path, 0.0)
    lost = _fly(tmp_path, 1.0)
    assert all(not _follows(log) for log in lost)  # drop 1.0: nothing heard, nothing followed

    # Vehicles pulled from afar: they began following a peer's best from beyond the target's
    # signal radius, where they read nothing themselves (vehicle 0, which starts inside it, may
    # follow too when a peer's best is stronger than its own).
    pulled = [
        i
        for i in range(VEHICLES)
        if (follows := _follows(shared[i])) and math.dist(follows[0]["pos"], TARGET) > SIGNAL_RADIUS
    ]
    assert pulled, "no vehicle followed a peer's best from beyond the signal radius"
    gained = []
    for i in pulled:
        follows = _follows(shared[i])
        first, last = follows[0], follows[-1]
        # Over the iterations that followed a peer's best, the follower closed on it...
        assert math.dist(last["pos"], last["best"]) < math.dist(first["pos"], first["best"]) - 500.0
        # ...and on the target the best was read from (the only one giving a signal).
        assert math.dist(last["pos"], TARGET) < math.dist(first["pos"], TARGET) - 500.0
        # Closing speed on the target over those iterations, against the same vehicle flown
        # without messages over the same search-time window: at least as fast (1 m/s of slack
        # for the tick interpolation), and for some follower much faster. How long the window
        # is varies (it ends when vehicle 0 confirms the target), so speeds, not distances.
        t0, t1 = first["t"] - _start(shared[i]), last["t"] - _start(shared[i])
        with_sharing = (math.dist(first["pos"], TARGET) - math.dist(last["pos"], TARGET)) / (
            t1 - t0
        )
        without = (_distance_at(lost[i], t0) - _distance_at(lost[i], t1)) / (t1 - t0)
        assert with_sharing > 8.0, (i, with_sharing)  # flying at 20 m/s
        assert with_sharing > without - 1.0, (i, with_sharing, without)
        gained.append(with_sharing - without)
    assert max(gained) > 3.0, gained
