"""field-duebendorf on stock ArduCopter SITL booted inside the site fence, NOT at the profile's
origin (one boot, three checks): the companion refuses a profile whose area lies 3 km away,
naming the distance; then it flies a shortened copy of field-duebendorf with virtual sensors in
the profile's own frame: transit from home to the profile's start point, a rehearsal target
confirmed, RTL, landed. A second connection (SERIAL1) judges: every GPS sample inside the
WGS84 fence, the start point reached, and the fence the vehicle stores equal to the profile's."""

from __future__ import annotations

import math
import os
import re
import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import yaml

from companion.fence_from_profile import guidance_fence, profile_frame
from companion.mission.start_point import start_point
from companion.telemetry.mission_log import read_records
from mdm_profiles import load_profile
from tests import sitl
from tests.companion.sitl_observer import Observer
from tests.waiting import wait_until

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

SPEEDUP = 5
HOME = (47.405893, 8.663214, 440.0)  # inside the Duebendorf fence, 1.9 km east of the origin
RTL = 6  # ArduCopter custom mode
ON_GROUND = 1  # MAV_LANDED_STATE_ON_GROUND
SOUTH_3KM = 3100.0 / 111_200.0  # degrees of latitude: home ends 3 km north of the area


def _field_copy(vehicles: int, *, south: float = 0.0) -> dict[str, Any]:
    """field-duebendorf, shortened: one real rehearsal target near the start point (set by the
    caller), sensors and level 2 of the SITL sensor test (a confirmation within minutes)."""
    p = load_profile("field-duebendorf").model_dump(mode="json", exclude_none=True)
    p["name"] = f"field-sitl-{os.getpid()}"
    p["fleet"]["vehicles"] = vehicles
    p["fleet"]["altitude_step"] = 0.0  # vehicle 12 would fly at 100 m: ArduCopter's FENCE_ALT_MAX
    p["sensor_source"] = {"kind": "virtual"}
    p["sensors"] = [
        {"name": "rf-detection", "radius": 400.0},
        {"name": "camera-confirmation", "radius": 60.0},
    ]
    p["policy"]["levels"] = [
        {"distribution": "LS", "step": 200.0},
        {
            "distribution": "BS",
            "step": 80.0,
            "index": {"gamma": 0.1, "index_max": 0.95, "index_min": 0.2, "kappa": 600.0},
        },
    ]
    p["mission"] = {"duration": 900.0, "ts_cap": 900.0}
    p["origin"]["lat"] -= south
    for vertex in p["site"]["geofence"]:
        vertex["lat"] -= south
    return p


def _write(path: Path, profile: dict[str, Any]) -> Path:
    path.write_text(yaml.safe_dump(profile, sort_keys=False))
    return path


def _inside(polygon: list[tuple[float, float]], lat: float, lon: float) -> bool:
    """Ray casting on (lat, lon) itself: the fence in WGS84, no frame of the companion's."""
    inside = False
    for (a_lat, a_lon), (b_lat, b_lon) in zip(polygon, polygon[1:] + polygon[:1], strict=True):
        if (a_lon > lon) != (b_lon > lon):
            cross = a_lat + (lon - a_lon) * (b_lat - a_lat) / (b_lon - a_lon)
            if lat < cross:
                inside = not inside
    return inside


def _metres(a: tuple[float, float], b: tuple[float, float]) -> float:
    north = math.radians(b[0] - a[0]) * 6_371_000.0
    east = math.radians(b[1] - a[1]) * 6_371_000.0 * math.cos(math.radians(a[0]))
    return math.hypot(north, east)


def _run(out: Path, profile: Path, inst: sitl.SitlInstance, seed: int) -> subprocess.Popen[bytes]:
    out.mkdir(parents=True, exist_ok=True)
    with (out / "companion.out").open("ab") as f:
        return subprocess.Popen(
            [sys.executable, "-m", "companion.cli", "run", "--profile", str(profile),
             "--vehicle", str(inst.index), "--connect", inst.companion_url, "--log-dir", str(out),
             "--seed", str(seed), "--land-wait", "400", "--flight-log-wait", "0"],
            stdout=f, stderr=subprocess.STDOUT, start_new_session=True,
            env=dict(os.environ, PYTHONUNBUFFERED="1"),
        )  # fmt: skip


def _stop(p: subprocess.Popen[bytes]) -> None:
    if p.poll() is None:
        os.killpg(p.pid, signal.SIGKILL)
        p.wait()


def _vehicle_fence(url: str, sysid: int) -> tuple[list[tuple[int, int]], float]:
    """The fence polygon the vehicle stores and FENCE_ENABLE, read on a connection of the
    test's own (mission protocol download, mission_type FENCE; PARAM_REQUEST_READ)."""
    conn = mavutil.mavlink_connection(url, source_system=251, source_component=190)
    try:
        fence = mavlink2.MAV_MISSION_TYPE_FENCE
        conn.mav.mission_request_list_send(sysid, 1, fence)
        count = conn.recv_match(type="MISSION_COUNT", blocking=True, timeout=10)
        assert count is not None, "no MISSION_COUNT for the fence"
        vertices = []
        for seq in range(count.count):
            conn.mav.mission_request_int_send(sysid, 1, seq, fence)
            item = conn.recv_match(type="MISSION_ITEM_INT", blocking=True, timeout=10)
            assert item is not None, f"no fence item {seq}"
            assert item.command == mavlink2.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
            vertices.append((item.x, item.y))
        conn.mav.mission_ack_send(sysid, 1, mavlink2.MAV_MISSION_ACCEPTED, fence)
        conn.mav.param_request_read_send(sysid, 1, b"FENCE_ENABLE", -1)
        value = conn.recv_match(type="PARAM_VALUE", blocking=True, timeout=10)
        assert value is not None, "no FENCE_ENABLE"
        return vertices, value.param_value
    finally:
        conn.close()


def test_field_profile_flies_in_its_frame_inside_the_fence_on_stock_arducopter(
    arducopter: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    # Refusal and field flight on one boot, the field search random: a bigger pack than stock
    # so the search, not the battery, ends the flight.
    inst = arducopter(speedup=SPEEDUP, home=",".join(map(str, (*HOME, 0))), battery_mah=20000)
    vehicles = inst.index + 1  # the companion's --vehicle is the SITL's index (sysid - 1)
    field = _field_copy(vehicles)
    polygon = [(v["lat"], v["lon"]) for v in field["site"]["geofence"]]
    obs = Observer(inst.observer_url, inst.sysid)
    flights: list[subprocess.Popen[bytes]] = []

    def context(out: Path) -> Callable[[], str]:
        return lambda: (
            f"observer: {obs.snapshot().modes} armed {obs.snapshot().armed}\n"
            f"{(out / 'companion.out').read_text(errors='replace')[-4000:]}"
        )

    try:
        # 1. The same vehicle against the profile moved 3.1 km south (the vehicle 3 km north of
        # its area, as if booted there; only the geometry matters): refused before arming.
        far = _write(tmp_path / "far.yaml", _field_copy(vehicles, south=SOUTH_3KM))
        refused = tmp_path / "refused"
        flights.append(_run(refused, far, inst, seed=0))
        assert flights[-1].wait(timeout=240) == 1, context(refused)()
        text = (refused / "companion.out").read_text()
        found = re.search(r"is (\d+) m (\S+) of the search area", text)
        assert found, text[-3000:]
        frame = profile_frame(load_profile(str(far)))
        north, east, _ = frame.to_local(*HOME)
        expected = north - 1200.0  # due north of the area's north edge (east inside the area)
        assert 0 < east < 2000.0
        assert abs(int(found.group(1)) - expected) <= 2, (found.group(0), expected)
        assert found.group(2) == "north"
        assert 2950 <= expected <= 3050
        assert not obs.snapshot().armed_ever
        refusal = next(line for line in text.splitlines() if "of the search area" in line)
        print(f"\nrefusal: {refusal}")

        # 2. The field mission: a seed whose start point is 300-800 m from home (a real transit,
        # a short test), the rehearsal target 90 m inside from that start point: outside the
        # confirmation radius when the search starts, close enough that the level-2 search finds
        # it within minutes whatever the vehicle index (at 150 m, vehicle 0 searched 900 s).
        profile = load_profile(str(_write(tmp_path / "probe.yaml", field)))
        fence = guidance_fence(profile)
        home_ne = profile_frame(profile).to_local(*HOME)[:2]
        seed, start = next(
            (s, st)
            for s in range(500)
            if 300.0
            <= math.dist(st := start_point(profile, s, inst.index, fence), home_ne)
            <= 800.0
        )
        centre = (600.0, 1000.0)
        toward = math.atan2(centre[1] - start[1], centre[0] - start[0])
        target = (
            round(start[0] + 90.0 * math.cos(toward), 1),
            round(start[1] + 90.0 * math.sin(toward), 1),
        )
        field["targets"] = [
            {"north": target[0], "east": target[1]},
            {"north": 200.0, "east": 1500.0, "false_target": True},
        ]
        path = _write(tmp_path / "field.yaml", field)
        out = tmp_path / "field"
        modes_before = len(obs.snapshot().modes)
        flights.append(_run(out, path, inst, seed=seed))

        def landed_after_rtl() -> bool:
            t = obs.snapshot()
            return t.landed_state == ON_GROUND and not t.armed and RTL in t.modes[modes_before:]

        wait_until(
            landed_after_rtl, 600.0, "confirmed, RTL, landed, disarmed", context=context(out)
        )
        assert flights[-1].wait(timeout=400) == 0, context(out)()
        records = read_records(out / f"mission-{inst.index}.jsonl")

        def first(event: str, **fields: object) -> dict[str, Any]:
            return next(
                r
                for r in records
                if r["event"] == event and all(r.get(k) == v for k, v in fields.items())
            )

        assert first("frame")["source"] == "GPS_GLOBAL_ORIGIN"
        begin, done = first("transit", state="begin"), first("transit", state="done")
        assert begin["distance"] >= 300.0
        assert (begin["to_north"], begin["to_east"]) == (round(start[0], 1), round(start[1], 1))
        search_start = first("phase", phase="search")["t"]
        assert search_start >= done["t"]
        (confirmation,) = [r for r in records if r["event"] == "confirmation"]
        assert (confirmation["north"], confirmation["east"]) == target
        assert first("end")["reason"] == "all targets"
        assert first("vehicle_fence", state="uploaded")["read_back"] == "equal"
        first("vehicle_fence", state="enabled")

        trace = obs.snapshot()
        airborne = [(lat, lon) for lat, lon, _alt, _mode in trace.track]  # alt > 1 m only
        outside = [p for p in airborne if not _inside(polygon, *p)]
        start_geo = profile_frame(profile).to_geodetic(*start, 0.0)[:2]
        closest = min(_metres(p, start_geo) for p in airborne)
        print(
            f"field mission: seed {seed}, transit {begin['distance']} m in {done['seconds']} s, "
            f"confirmed at t={confirmation['t']} s; observer: {len(airborne)} airborne GPS "
            f"samples, {len(outside)} outside the fence, closest to the start point "
            f"{closest:.1f} m, {trace.distance:.0f} m flown, max {trace.max_alt:.1f} m, "
            f"modes {trace.modes}; map {out / f'map-{inst.index}.png'}"
        )
        assert len(airborne) >= 100
        assert outside == [], f"{len(outside)} of {len(airborne)} samples outside: {outside[:5]}"
        assert closest <= 15.0, "the vehicle never reached its start point: wrong frame?"
        assert trace.max_alt >= 0.9 * field["fleet"]["altitude"]
        assert (out / f"map-{inst.index}.png").stat().st_size > 10_000
    finally:
        for p in flights:
            _stop(p)
        obs.close()

    # 3. The fence the vehicle keeps, read on a connection of the test's own.
    vertices, enabled = _vehicle_fence(inst.observer_url, inst.sysid)
    assert vertices == [(round(lat * 1e7), round(lon * 1e7)) for lat, lon in polygon]
    assert enabled == 1.0
    print(f"vehicle fence read back: {len(vertices)} vertices equal, FENCE_ENABLE {enabled:g}")
