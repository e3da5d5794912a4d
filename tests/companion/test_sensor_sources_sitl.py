"""Sensor sources on stock ArduCopter SITL (one boot, two flights): the companion's virtual
sensors confirm a rehearsal target, then MQTT detections published by the test switch the level
and confirm; each flight ends with RTL, seen landed and disarmed from a second connection.

The profile's origin is the vehicle's home, so the autopilot's local frame (its EKF origin, the
boot point) is the profile's frame: these tests are about the sensors, not the frame."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from companion.link.local_frame import LocalFrame
from companion.telemetry.mission_log import read_records
from tests import sitl
from tests.companion.sitl_observer import Observer
from tests.mqtt_harness import publish
from tests.profile_files import levels, sensors, write_profile_with
from tests.waiting import wait_until

SPEEDUP = 5
HOME = (47.405893, 8.663214, 440.0)  # inside the Duebendorf fence
RTL = 6  # ArduCopter custom mode
ON_GROUND = 1  # MAV_LANDED_STATE_ON_GROUND


def _profile(path: Path, vehicles: int) -> Path:
    lat, lon, alt = HOME
    return write_profile_with(
        path,
        f"sitl-sensors-{os.getpid()}",
        area={"north": 600.0, "east": 600.0},
        origin={"lat": lat, "lon": lon, "alt": alt},
        targets=[
            {"north": 220.0, "east": 160.0},
            {"north": 60.0, "east": 300.0, "false_target": True},
        ],
        fleet={
            "vehicles": vehicles,
            "speed": 10.0,
            "tau": 0.5,
            "altitude": 20.0,
            "altitude_step": 0.0,
        },
        sensors=sensors(400.0, 60.0),
        sensor_source={"kind": "virtual", "silence_timeout": 30.0},
        policy={"levels": levels(200.0, 80.0, 600.0)},
        mission={"duration": 900.0, "ts_cap": 900.0},
    )


def _run(out: Path, profile: Path, inst: sitl.SitlInstance, *extra: str) -> subprocess.Popen[bytes]:
    out.mkdir(parents=True, exist_ok=True)
    with (out / "companion.out").open("ab") as f:
        return subprocess.Popen(
            [sys.executable, "-m", "companion.cli", "run", "--profile", str(profile),
             "--vehicle", str(inst.index), "--connect", inst.companion_url, "--log-dir", str(out),
             "--land-wait", "300", "--flight-log-wait", "0", *extra],
            stdout=f, stderr=subprocess.STDOUT, start_new_session=True,
            env=dict(os.environ, PYTHONUNBUFFERED="1"),
        )  # fmt: skip


def _stop(p: subprocess.Popen[bytes]) -> None:
    if p.poll() is None:
        os.killpg(p.pid, signal.SIGKILL)
        p.wait()


def test_virtual_then_mqtt_sensors_confirm_on_stock_arducopter(
    arducopter: Callable[..., sitl.SitlInstance], mqtt_broker: int, tmp_path: Path
) -> None:
    # Two searches on one boot: a random first search can take 5 vehicle minutes, which drains
    # the stock pack below the companion's 20 % end; the second flight is about the sensors.
    inst = arducopter(speedup=SPEEDUP, home=",".join(map(str, (*HOME, 0))), battery_mah=20000)
    profile = _profile(tmp_path / "profile.yaml", vehicles=inst.index + 1)
    obs = Observer(inst.observer_url, inst.sysid)
    flights: list[subprocess.Popen[bytes]] = []

    def context(out: Path) -> Callable[[], str]:
        return lambda: (
            f"trace {obs.snapshot()}\ncompanion:\n"
            f"{(out / 'companion.out').read_text(errors='replace')[-3000:]}"
        )

    def events(out: Path) -> list[dict[str, Any]]:
        return read_records(out / f"mission-{inst.index}.jsonl")

    modes_before = 0

    def landed_after_rtl() -> bool:
        t = obs.snapshot()
        return t.landed_state == ON_GROUND and not t.armed and RTL in t.modes[modes_before:]

    try:
        # 1. Virtual sensors: the profile's targets against the vehicle's real position.
        virtual = tmp_path / "virtual"
        flights.append(_run(virtual, profile, inst))
        wait_until(
            landed_after_rtl,
            400.0,
            "virtual: confirmed, RTL, landed, disarmed",
            context=context(virtual),
        )
        assert flights[-1].wait(timeout=400) == 0, context(virtual)()
        records = events(virtual)
        (confirmation,) = [r for r in records if r["event"] == "confirmation"]
        assert (confirmation["north"], confirmation["east"]) == (220.0, 160.0)
        assert next(r for r in records if r["event"] == "end")["reason"] == "all targets"
        first = obs.snapshot()
        assert first.max_alt >= 15.0
        assert first.distance >= 100.0, context(virtual)()
        assert (virtual / f"map-{inst.index}.png").stat().st_size > 10_000
        print(
            f"\nvirtual on ArduCopter: confirmed at t={confirmation['t']} s; observer: "
            f"{first.distance:.0f} m flown, max {first.max_alt:.1f} m, modes {first.modes}; "
            f"map {virtual / f'map-{inst.index}.png'}"
        )

        # 2. MQTT: the test is the detector.
        mqtt = tmp_path / "mqtt"
        prefix = f"mdm/sitl-{os.getpid()}"
        topic = f"{prefix}/uav{inst.index}/detections"
        modes_before = len(obs.snapshot().modes)
        flights.append(_run(mqtt, profile, inst, "--sensor-source", "mqtt", "--mqtt",
                            f"127.0.0.1:{mqtt_broker}", "--mqtt-prefix", prefix))  # fmt: skip
        wait_until(
            lambda: any(r.get("phase") == "search" for r in events(mqtt)),
            200.0,
            "mqtt: searching",
            context=context(mqtt),
        )
        frame = LocalFrame(*HOME)
        lat, lon, _ = frame.to_geodetic(400.0, 450.0, 0.0)

        # As a detector does, each sighting is sent once a second, freshly stamped, until the
        # companion acts on it: a frame stamped before its switch to that sensor is not counted
        # (MqttSensorSource.select), and the switch may come just after the log line waited on.
        def sighting(payload: dict[str, object], done: Callable[[], bool]) -> Callable[[], bool]:
            sent = [-1.0]

            def observe() -> bool:
                if time.monotonic() - sent[0] >= 1.0:
                    frame = json.dumps({**payload, "time": time.time()})
                    assert publish(mqtt_broker, topic, frame).returncode == 0
                    sent[0] = time.monotonic()
                return done()

            return observe

        detection = {"sensor": "detection", "lat": lat, "lon": lon}
        wait_until(
            sighting(
                detection,
                lambda: any(r["event"] == "level" and r["level"] == 1 for r in events(mqtt)),
            ),
            20.0,
            "mqtt: level 1",
            context=context(mqtt),
        )
        confirm = {"sensor": "confirmation", "north": 400.0, "east": 450.0, "confidence": 0.9}
        wait_until(
            sighting(confirm, lambda: any(r["event"] == "confirmation" for r in events(mqtt))),
            60.0,
            "mqtt: confirmed",
            context=context(mqtt),
        )
        wait_until(
            landed_after_rtl, 300.0, "mqtt: confirmed, RTL, landed, disarmed", context=context(mqtt)
        )
        assert flights[-1].wait(timeout=400) == 0, context(mqtt)()
        records = events(mqtt)
        (confirmation,) = [r for r in records if r["event"] == "confirmation"]
        assert (confirmation["north"], confirmation["east"]) == (400.0, 450.0)
        assert next(r for r in records if r["event"] == "end")["reason"] == "all targets"
        print(
            f"mqtt on ArduCopter: level 1 and confirmation from published detections at "
            f"t={confirmation['t']} s; modes {obs.snapshot().modes}"
        )
    finally:
        for p in flights:
            _stop(p)
        obs.close()
