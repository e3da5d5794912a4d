"""docker/compose.sitl.yaml for real against stock SITL autopilots on the host (ArduCopter, PX4
SIH: the autopilot is a test parameter): two instances (the first free indices from
MDM_SITL_INSTANCE_BASE), the broker and two companions in containers on the host's network, a
short search flown to the landing. What the vehicles did is read from a second link of each
instance (ArduCopter SERIAL1, PX4's GCS link), never from the companions' logs; the logs and the
MQTT events are read from the host; `down -v` leaves nothing behind."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from companion.telemetry import read_records
from tests import sitl
from tests.companion.sitl_observer import Observer
from tests.docker.stack import Stack, all_events, project
from tests.mqtt_harness import free_port

SPEEDUP = {"arducopter": 5.0, "px4": 3.0}
"""The speed-ups tests/companion/test_sitl_flights.py found stable on 2 shared cores: PX4 at 5x
under load outran its companion's setpoints (CI of 2026-12-02: a PX4 vehicle here ended
"climb timeout" at 5x while two SITL lanes flew beside it)."""
HOME = (47.3960, 8.6380, 440.0)
"""The profile's origin and every vehicle's home: the autopilot's local frame is the profile's."""
ON_GROUND = 1  # MAV_LANDED_STATE_ON_GROUND
MISSION_WALL_S = 300.0
PROFILE = "docker-sitl"


def _profile(folder: Path, vehicles: int) -> None:
    """A 600 m square, a 60 s search: take-off, search, RTL and landing in about a minute."""
    folder.mkdir(mode=0o755)
    folder.chmod(0o755)  # mounted into the containers, read there by uid 10001
    lat, lon, alt = HOME
    path = folder / f"{PROFILE}.yaml"
    path.write_text(f"""
name: {PROFILE}
area: {{north: 600.0, east: 600.0}}
origin: {{lat: {lat}, lon: {lon}, alt: {alt}}}
targets:
  - {{north: 300.0, east: 300.0}}
fleet: {{vehicles: {vehicles}, speed: 10.0, tau: 0.5, altitude: 20.0, altitude_step: 5.0}}
sensors:
  - {{name: detection, radius: 200.0}}
  - {{name: confirmation, radius: 40.0}}
policy:
  kind: mdm
  levels:
    - {{distribution: LS, step: 200.0}}
    - distribution: BS
      step: 80.0
      index: {{gamma: 0.1, index_max: 0.95, index_min: 0.2, kappa: 600.0}}
mission: {{duration: 60.0, ts_cap: 600.0}}
""")
    path.chmod(0o644)


@pytest.fixture(params=["arducopter", "px4"])
def instances(
    request: pytest.FixtureRequest, sitl_start: Callable[..., sitl.SitlInstance]
) -> list[sitl.SitlInstance]:
    """Two instances of the autopilot, homed at the profile's origin (ArduCopter's home takes
    a heading too)."""
    home = ",".join(map(str, HOME if request.param == "px4" else (*HOME, 0)))
    return [sitl_start(request.param, speedup=SPEEDUP[request.param], home=home) for _ in range(2)]


@pytest.fixture
def stack(
    docker_images: None, instances: list[sitl.SitlInstance], tmp_path: Path
) -> Iterator[Stack]:
    profiles = tmp_path / "profiles"
    _profile(profiles, vehicles=max(i.index for i in instances) + 1)
    settings = {
        "MDM_PROFILES": str(profiles),
        "MDM_PROFILE": f"/opt/mdm/mission_profiles/{PROFILE}.yaml",
        "MDM_FLIGHT_LOG_WAIT": "0",  # not about the log (PX4 sends it at about 13 kB/s)
    }
    for n, inst in enumerate(instances):
        settings |= {f"MDM_VEHICLE_{n}": str(inst.index), f"MDM_CONNECT_{n}": inst.companion_url}
    vehicles = [i.index for i in instances]
    with project("compose.sitl.yaml", tmp_path, vehicles, free_port(), settings) as stack:
        yield stack


@pytest.mark.timeout(900)
def test_compose_sitl_flies_stock_autopilots_to_the_landing(
    stack: Stack, instances: list[sitl.SitlInstance], tmp_path: Path
) -> None:
    observers = [Observer(i.observer_url, i.sysid) for i in instances]
    companions = [f"companion-{n}" for n in range(len(instances))]
    try:
        stack.compose("up", "-d", "mosquitto")
        stack.broker_ready()
        sub = stack.subscriber("mdm/#", tmp_path / "mqtt.txt", "monitor")
        start = time.monotonic()
        stack.compose("up", "-d", *companions)
        codes = stack.wait_exit(companions, MISSION_WALL_S)
        print(f"SITL mission (up to the last companion's exit): {time.monotonic() - start:.1f} s")
        logs = stack.compose("logs", "--no-color", *companions).stdout
        assert codes == ["0"] * len(companions), f"exit codes {codes}\n{logs[-4000:]}"
        runs = tmp_path / "runs"
        stack.compose("cp", "companion-0:/home/mdm/runs", str(runs))
        for inst, obs in zip(instances, observers, strict=True):
            trace = obs.snapshot()
            print(
                f"instance {inst.index}: {trace.distance:.0f} m flown, max {trace.max_alt:.1f} m,"
                f" modes {trace.modes}, landed_state {trace.landed_state}, armed {trace.armed}"
            )
            assert trace.armed_ever, f"instance {inst.index} never armed\n{logs[-4000:]}"
            assert trace.max_alt >= 15.0
            assert trace.distance >= 200.0
            assert trace.landed_state == ON_GROUND
            assert not trace.armed
            events = read_records(runs / f"mission-{inst.index}.jsonl")
            ends = [e["reason"] for e in events if e["event"] == "end"]
            assert ends == ["mission time"], ends
            logged = [r for r in events if r["event"] != "tick"]
            topic = f"mdm/{PROFILE}/uav{inst.index}/event"
            published = all_events(sub, topic, len(logged))
            assert [e["seq"] for e in published] == list(range(len(logged)))
            assert [{k: v for k, v in e.items() if k != "seq"} for e in published] == [
                {**r, "vehicle": inst.index} for r in logged
            ], f"uav{inst.index}: MQTT != log"
    finally:
        for obs in observers:
            obs.close()
