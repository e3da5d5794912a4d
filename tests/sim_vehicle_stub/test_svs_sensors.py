"""The sensor protocol: MDM_SENSOR selects the one sensor that reports; SENS_SIG and DET/CNF
DEBUG_VECT carry the readings; ground truth goes to the event log only."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest

from mdm_profiles import builtin_profile
from tests.emulator_harness import Client, free_udp_base, make_config, running_emulator

PROFILE = builtin_profile("paper-fixed-false")  # T3 (index 2) is false
R_DET, R_CNF = 2000.0, 400.0
ALLOWED = {
    "HEARTBEAT",
    "SYS_STATUS",
    "SYSTEM_TIME",
    "BATTERY_STATUS",
    "EXTENDED_SYS_STATE",
    "GPS_RAW_INT",
    "HOME_POSITION",
    "GLOBAL_POSITION_INT",
    "LOCAL_POSITION_NED",
    "ATTITUDE",
    "PARAM_VALUE",
    "NAMED_VALUE_FLOAT",
    "DEBUG_VECT",
    "COMMAND_ACK",
    "STATUSTEXT",
    "MISSION_CURRENT",
    "VFR_HUD",  # the vehicle's own speed, heading and altitude, as GLOBAL_POSITION_INT
}


def _readings(c: Client, seconds: float) -> tuple[list[float], list[Any]]:
    sig: list[float] = []
    vec: list[Any] = []

    def grab(m: Any) -> bool:
        if m.get_type() == "NAMED_VALUE_FLOAT" and m.name == "SENS_SIG":
            sig.append(float(m.value))
        if m.get_type() == "DEBUG_VECT":
            vec.append(m)
        return False

    c.pump(seconds, grab)
    return sig, vec


@pytest.mark.timeout(60)
def test_only_the_selected_sensor_reports_and_false_targets_never_confirm(tmp_path: Path) -> None:
    events = tmp_path / "events.jsonl"
    base = free_udp_base(2)
    cfg = make_config(
        2,
        base,
        profile=PROFILE,
        events=events,
        start_positions=((2000.0, 1700.0), (10000.0, 9700.0)),
    )
    with running_emulator(cfg), Client(base, 1) as real:
        types: set[str] = set()
        assert real.pump(2, lambda m: m.get_type() == "HEARTBEAT") is not None
        sig, vec = _readings(real, 1.0)
        assert sig == []
        assert vec == []
        # Detection sensor on (PX4 integer parameter, bytewise).
        assert real.set_param("MDM_SENSOR", 0, int_bytewise=True) is not None
        sig, vec = _readings(real, 1.0)
        assert sig
        assert sig[-1] == pytest.approx(math.exp(-300.0 / R_DET), abs=1e-4)
        assert {v.name for v in vec} == {"DET"}
        last = vec[-1]
        # The target at (2000, 2000), from the vehicle's boot point (2000, 1700).
        assert (last.x, last.y) == (0.0, 300.0)
        assert last.z == pytest.approx(sig[-1], abs=1e-4)
        boot_ms = real.last["LOCAL_POSITION_NED"].time_boot_ms
        assert abs(last.time_usec / 1000 - boot_ms) < 1000
        # Confirmation sensor: the same target, stronger-falling signal, name CNF.
        assert real.set_param("MDM_SENSOR", 1, int_bytewise=True) is not None
        real.pump(0.2)
        sig, vec = _readings(real, 1.0)
        assert sig[-1] == pytest.approx(math.exp(-300.0 / R_CNF), abs=1e-4)
        assert {v.name for v in vec} == {"CNF"}
        # Off again: silence.
        assert real.set_param("MDM_SENSOR", -1, int_bytewise=True) is not None
        real.pump(0.2)
        sig, vec = _readings(real, 0.5)
        assert sig == []
        assert vec == []
        types |= set(real.last)

        # Vehicle 2 sits 300 m from false target T3: detection fires, confirmation never does.
        with Client(base + 1, 2) as false:
            assert false.pump(2, lambda m: m.get_type() == "HEARTBEAT") is not None
            assert false.set_param("MDM_SENSOR", 0, int_bytewise=True) is not None
            sig, vec = _readings(false, 1.0)
            assert {(v.x, v.y) for v in vec} == {(0.0, 300.0)}  # (10000, 10000) from its boot point
            assert false.set_param("MDM_SENSOR", 1, int_bytewise=True) is not None
            false.pump(0.2)
            sig, vec = _readings(false, 1.0)
            assert vec == []
            assert max(sig) < 0.01
            types |= set(false.last)
        assert types <= ALLOWED

    log = [json.loads(line) for line in events.read_text().splitlines()]
    kinds = {(e["event"], e.get("vehicle"), e.get("target")) for e in log}
    assert sum(e["event"] == "target_appeared" for e in log) == 10
    assert ("detected", 0, 0) in kinds
    assert ("confirmed", 0, 0) in kinds
    assert ("detected", 1, 2) in kinds
    assert ("confirmed", 1, 2) not in kinds
    confirmed = next(e for e in log if e["event"] == "confirmed")
    assert (confirmed["north"], confirmed["east"]) == (2000.0, 2000.0)
