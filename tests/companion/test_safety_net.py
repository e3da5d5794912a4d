"""The safety net the companion puts into the autopilot before the first arm
(``failsafe.safety_net``), against the emulator's two personas over UDP: ``set`` leaves the
autopilot's own parameters as needed (read from the emulated autopilot's table, not from the
companion), records each before and after, prints what it changed; ``check`` refuses to arm
with exit 2 naming each wrong parameter and its value; ``off`` writes nothing; a write the
autopilot refuses stops the start before arming, naming the parameter."""

from __future__ import annotations

import asyncio
import logging
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import yaml

from companion.fly import fly
from companion.link.pymavlink_link import PymavlinkLink
from companion.telemetry.mission_log import read_records
from mdm_profiles import MissionProfile, load_profile
from sim_vehicle_stub.emulator import Emulator
from tests.emulator_harness import free_udp_base, make_config, running_emulator
from tests.waiting import wait_until_async

FIELD = load_profile("field-duebendorf")
INSIDE = ((600.0, 1000.0),)  # a start position inside the site's fence
LAYER = FIELD.fleet.altitude  # vehicle 0's layer
CEILING = 120.0  # the field profile's site.max_altitude (the default)

# What the safety net must leave in each autopilot (docs/companion.md), the companion's system
# id 245 being the GCS ArduCopter watches; loss times depend on the vehicle's clock (below).
NEEDED = {
    "px4": {
        "GF_ACTION": 3.0,
        "COM_OBL_RC_ACT": 3.0,
        "COM_LOW_BAT_ACT": 3.0,
        "BAT_CRIT_THR": 0.10,
        "RTL_RETURN_ALT": LAYER,
    },
    "ardupilot": {
        "FENCE_ENABLE": 1.0,
        "FENCE_ACTION": 1.0,
        "FS_GCS_ENABLE": 1.0,
        "MAV_GCS_SYSID": 245.0,
        "BATT_FS_LOW_ACT": 2.0,
        "RTL_ALT": LAYER * 100.0,
    },
}
ABOVE_LAYER = {  # in [layer + 2 m (the layer band), the ceiling]; lower is stricter
    "px4": {"GF_MAX_VER_DIST": (LAYER + 2.0, CEILING)},
    "ardupilot": {
        "FENCE_ALT_MAX": (LAYER + 2.0, CEILING),
        "BATT_LOW_MAH": (520.0, 2600.0),  # 10 % to half of the persona's BATT_CAPACITY 5200
    },
}
WRONG = {  # stock values where the persona's default is already as needed
    "px4": {
        "COM_OBL_RC_ACT": 0.0,
        "GF_ACTION": 2.0,
        "RTL_RETURN_ALT": 30.0,
        "GF_MAX_VER_DIST": 0.0,  # PX4's stock: no altitude fence
    },
    "ardupilot": {"FS_GCS_ENABLE": 0.0, "BATT_FS_LOW_ACT": 0.0, "FENCE_ACTION": 0.0},
}


def _with_net(profile: MissionProfile, mode: str, **site: Any) -> MissionProfile:
    failsafe = profile.failsafe.model_copy(update={"safety_net": mode})
    assert profile.site is not None
    return profile.model_copy(
        update={"failsafe": failsafe, "site": profile.site.model_copy(update=site)}
    )


def _set_wrong(emu: Emulator, persona: str) -> None:
    v = emu.vehicles[0]
    for name, value in WRONG[persona].items():
        v.params.set(name, value)
    v.apply_params()


def _arm_and_stop(profile: MissionProfile, base: int, log_dir: Path, **options: Any) -> str:
    """Fly vehicle 0 until it is armed (or the mission ended), then stop it; the end reason.
    ``options``: more of the mission's configuration (companion.fly's keywords)."""

    async def main() -> str:
        link = PymavlinkLink(url=f"udpin:127.0.0.1:{base}", target_system=1)
        async with fly(
            profile, 0, link, log_dir=log_dir, land_wait=0.0, sensor_source="virtual", **options
        ) as flight:
            await wait_until_async(
                lambda: (flight.mission.seen.heartbeat, flight.mission.end_reason),
                60.0,
                "armed or ended",
                until=lambda s: s[1] is not None or (s[0] is not None and s[0].armed),
            )
            flight.stop()
            return await asyncio.wait_for(flight.ended(), 60.0)

    return asyncio.run(main())


def _net(log_dir: Path) -> dict[str, Any]:
    (net,) = [r for r in read_records(log_dir / "mission-0.jsonl") if r["event"] == "safety_net"]
    return net


@pytest.mark.timeout(120)
@pytest.mark.parametrize("persona", ["px4", "ardupilot"])
def test_set_writes_reads_back_and_records_each_parameter(
    persona: str, tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    base = free_udp_base(1)
    config = make_config(
        1, base, profile=FIELD, speedup=20.0, personas=(persona,), start_positions=INSIDE
    )
    caplog.set_level(logging.INFO, logger="companion.mission.safety_net")
    with running_emulator(config) as emu:
        _set_wrong(emu, persona)
        _arm_and_stop(_with_net(FIELD, "set"), base, tmp_path)
        params = emu.vehicles[0].params
        held = {name: params.get(name) for name in NEEDED[persona]}
        ranged = {name: params.get(name) for name in ABOVE_LAYER[persona]}
        limits = emu.vehicles[0].limits
    assert held == pytest.approx(NEEDED[persona]), held
    for name, (low, high) in ABOVE_LAYER[persona].items():
        assert low <= ranged[name] <= high, (name, ranged[name])
    if persona == "px4":
        assert limits.setpoint[1].name == "RTL"  # the persona acts on them as PX4 does
        assert limits.battery[0] == pytest.approx(0.10)
        assert limits.battery[1].name == "RTL"
    else:
        assert limits.link[1].name == "RTL"
        assert limits.fence_rules is not None
        assert limits.fence_rules.alt_max == ranged["FENCE_ALT_MAX"]  # FENCE_TYPE bit 1 set
    net = _net(tmp_path)
    assert net["mode"] == "set"
    assert net["state"] == "ok"
    rows = {r["name"]: r for r in net["params"]}
    for name, value in WRONG[persona].items():
        assert rows[name]["before"] == pytest.approx(value), rows[name]
        assert rows[name]["after"] == pytest.approx(
            NEEDED[persona].get(name, CEILING)  # GF_MAX_VER_DIST written: the ceiling
        ), rows[name]
        assert any(f"safety net: {name} " in m for m in caplog.messages), caplog.messages
    assert set(NEEDED[persona]) <= set(rows)
    # the loss time in the vehicle's seconds: about 5 wall s at the emulator's speed-up
    loss = "COM_OF_LOSS_T" if persona == "px4" else "FS_GCS_TIMEOUT"
    assert rows[loss]["after"] <= 5.0 * 20.0 * 1.3, rows[loss]


@pytest.mark.timeout(120)
def test_off_writes_nothing(tmp_path: Path) -> None:
    base = free_udp_base(1)
    config = make_config(1, base, profile=FIELD, speedup=20.0, start_positions=INSIDE)
    with running_emulator(config) as emu:
        _set_wrong(emu, "px4")
        _arm_and_stop(_with_net(FIELD, "off"), base, tmp_path)
        params = emu.vehicles[0].params
        held = {name: params.get(name) for name in WRONG["px4"]}
    assert held == WRONG["px4"]
    assert _net(tmp_path) == {"event": "safety_net", "t": _net(tmp_path)["t"], "mode": "off"}


def _companion(profile: MissionProfile, base: int, out: Path) -> subprocess.CompletedProcess[str]:
    path = out / "profile.yaml"
    path.write_text(yaml.safe_dump(profile.model_dump(mode="json")))
    return subprocess.run(
        [sys.executable, "-m", "companion.cli", "run", "--profile", str(path), "--vehicle", "0",
         "--connect", f"udpin:127.0.0.1:{base}", "--log-dir", str(out), "--sensor-source", "virtual",
         "--land-wait", "0", "--no-map", "--no-tlog"],
        check=False, capture_output=True, text=True, timeout=90,
    )  # fmt: skip


@pytest.mark.timeout(120)
@pytest.mark.parametrize("persona", ["px4", "ardupilot"])
def test_check_refuses_to_arm_with_exit_2_naming_each_wrong_parameter(
    persona: str, tmp_path: Path
) -> None:
    base = free_udp_base(1)
    config = make_config(
        1, base, profile=FIELD, speedup=20.0, personas=(persona,), start_positions=INSIDE
    )
    with running_emulator(config) as emu:
        _set_wrong(emu, persona)
        done = _companion(_with_net(FIELD, "check"), base, tmp_path)
        armed = emu.vehicles[0].armed
        held = {name: emu.vehicles[0].params.get(name) for name in WRONG[persona]}
    out = done.stdout + done.stderr
    assert done.returncode == 2, out
    assert not armed
    assert held == WRONG[persona]  # checked, not written
    for name, value in WRONG[persona].items():
        assert f"{name} is {value:g}, needs" in out, out
    net = _net(tmp_path)
    assert net["state"] == "refused"
    assert {r["name"]: r["after"] for r in net["params"]} | WRONG[persona] == {
        r["name"]: r["after"] for r in net["params"]
    }


@pytest.mark.timeout(120)
def test_a_write_the_autopilot_refuses_stops_the_start_naming_it(tmp_path: Path) -> None:
    """ArduCopter's FENCE_ALT_MAX goes up to 1000 m (the persona's range, as the real one): a
    layer at 1100 m under a site ceiling of 1200 m cannot be fenced, and the vehicle is not
    armed."""
    base = free_udp_base(1)
    fleet = FIELD.fleet.model_copy(update={"altitude": 1100.0})
    profile = _with_net(FIELD, "set", max_altitude=1200.0).model_copy(update={"fleet": fleet})
    config = make_config(
        1, base, profile=profile, speedup=20.0, personas=("ardupilot",), start_positions=INSIDE
    )
    with running_emulator(config) as emu:
        done = _companion(profile, base, tmp_path)
        armed = emu.vehicles[0].armed
    out = done.stdout + done.stderr
    assert done.returncode == 2, out
    assert not armed
    assert "FENCE_ALT_MAX 100 -> 1200 not confirmed (read back: 100)" in out, out
