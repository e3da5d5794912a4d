"""A broker of its own on a spare port, stopped for 30 wall seconds mid-mission and started
again: the companions keep flying, buffer their events on disk, and deliver every one, in
order, when the broker is back; a persistent-session subscriber (mosquitto_sub) counts them
against the mission logs."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from companion.telemetry import read_records
from mdm_ground.fleet.runner import FleetOptions, run_fleet
from tests.mqtt_harness import Broker, Subscriber, publish
from tests.profile_files import levels, write_profile_with
from tests.waiting import wait_until

pytestmark = pytest.mark.usefixtures("fleet_processes")

# False targets all over the area: detections, level switches and fallbacks keep coming,
# and the one real target (50 m confirmation radius, in a corner) is not found in the test.
PREFIX = "mdm/outage"
OUTAGE = 30.0


@pytest.mark.timeout(180)
def test_events_survive_a_30_s_broker_outage_complete_and_in_order(
    mosquitto: Callable[..., Broker], tmp_path: Path
) -> None:
    # One real target in a corner and four false ones: a long search, many events.
    real = [{"north": 2950.0, "east": 2950.0}]
    false = [
        {"north": n, "east": e, "false_target": True}
        for n, e in ((800.0, 800.0), (800.0, 2200.0), (2200.0, 800.0), (1500.0, 1500.0))
    ]
    profile = write_profile_with(
        tmp_path / "profile.yaml",
        "mqtt-outage-test",
        targets=real + false,
        policy={"levels": levels(600.0, 300.0, 30.0)},
    )
    out = tmp_path / "run"
    broker = mosquitto()
    broker.start()
    sub = Subscriber(broker.port, f"{PREFIX}/#", tmp_path / "sub.txt", persistent=True)

    def arrived(i: int) -> list[int]:
        """seq of vehicle i's events in arrival order, duplicates included."""
        return [m.json()["seq"] for m in sub.messages("event") if f"/uav{i}/" in m.topic]

    def logged(i: int) -> list[dict[str, Any]]:
        return [r for r in read_records(out / f"mission-{i}.jsonl") if r["event"] != "tick"]

    fleet = threading.Thread(target=run_fleet, args=(FleetOptions(
        profile=str(profile), out=out, speedup=10.0, duration=5000.0, seed=5,
        wall_limit=150, mqtt_args=("--mqtt", f"127.0.0.1:{broker.port}", "--mqtt-prefix", PREFIX)),
    ))  # fmt: skip
    try:
        sub.ready(broker.port, f"{PREFIX}/probe")
        fleet.start()
        wait_until(
            lambda: (
                all(any(r.get("phase") == "search" for r in logged(i)) for i in (0, 1))
                and all(len(arrived(i)) == len(logged(i)) for i in (0, 1))
            ),
            60,
            "both vehicles searching, their events delivered",
        )
        broker.stop()
        at_stop = [len(logged(i)) for i in (0, 1)]
        time.sleep(OUTAGE)  # the outage under test
        at_restart = [len(logged(i)) for i in (0, 1)]
        received_during = [len(set(arrived(i))) for i in (0, 1)]
        broker.start()
        wait_until(
            lambda: all(len(set(arrived(i))) >= at_restart[i] for i in (0, 1)),
            30,
            "the events of the outage delivered",
        )
        assert publish(broker.port, f"{PREFIX}/all/cmd", '{"command": "abort"}').returncode == 0
        fleet.join(60)
        assert not fleet.is_alive(), "the fleet did not end after abort"
        wait_until(
            lambda: all(len(set(arrived(i))) == len(logged(i)) for i in (0, 1)),
            15,
            "the last events delivered",
        )
    finally:
        sub.stop()
        broker.stop()
    for i in (0, 1):
        assert at_restart[i] - at_stop[i] >= 3, f"vehicle {i}: too few events in the outage"
        assert received_during[i] <= at_stop[i]  # nothing arrives while the broker is down
        seqs = arrived(i)
        first = list(dict.fromkeys(seqs))  # first arrival of each seq, in arrival order
        assert first == list(range(len(logged(i)))), f"vehicle {i}: missing or out of order"
        events: dict[int, dict[str, Any]] = {}
        for m in sub.messages("event"):
            e = m.json()
            if f"/uav{i}/" in m.topic:
                events.setdefault(e["seq"], {k: v for k, v in e.items() if k != "seq"})
        assert [events[s] for s in first] == [r | {"vehicle": i} for r in logged(i)]
        print(
            f"vehicle {i}: {at_stop[i]} events before the outage, "
            f"{at_restart[i] - at_stop[i]} during it, {len(first) - at_restart[i]} after; "
            f"{len(seqs) - len(first)} duplicate(s)"
        )
        assert next(r for r in logged(i) if r["event"] == "end")["reason"] == "operator abort"
