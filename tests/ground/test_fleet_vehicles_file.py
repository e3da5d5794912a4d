"""`companion fleet --vehicles-file`: each refusal before anything arms (exit 2, the vehicle named,
no companion started). Where a vehicle must answer, the emulator over real UDP is that vehicle
(one process, a real MAVLink endpoint); the SITL flights are in test_fleet_sitl_team.py."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml

from companion.cli import main
from tests.emulator_harness import Client, free_udp_base, make_config, mavutil, running_emulator

ARM = mavutil.mavlink.MAV_CMD_COMPONENT_ARM_DISARM
FORCE = 21196.0  # MAV_CMD_COMPONENT_ARM_DISARM param 2: arm whatever the checks say


def _fleet_file(folder: Path, *entries: dict[str, Any]) -> Path:
    path = folder / "fleet.yaml"
    path.write_text(yaml.safe_dump({"vehicles": list(entries)}, sort_keys=False))
    return path


def _refused(capsys: pytest.CaptureFixture[str], tmp_path: Path, path: Path, *extra: str) -> str:
    out = tmp_path / "run"
    code = main(["fleet", "--quiet", "--profile", "field-duebendorf", "--vehicles-file", str(path),
                 "--out", str(out), *extra])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2, err
    assert not list(out.glob("mission-*.jsonl")), "a refused run started a companion"
    assert not (out / "results.json").exists()
    return err


def _entry(index: int, port: int, system_id: int, **more: Any) -> dict[str, Any]:
    return {"index": index, "link": f"udpin:127.0.0.1:{port}", "system_id": system_id, **more}


def test_a_system_id_used_twice_is_refused_naming_both_entries(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    path = _fleet_file(tmp_path, _entry(0, 24001, 8), _entry(1, 24002, 8))
    err = _refused(capsys, tmp_path, path)
    assert "vehicles[1] (vehicle 1 (system 8, udpin:127.0.0.1:24002)): system_id 8 already " \
           "used by vehicles[0]" in err  # fmt: skip


def test_a_link_used_twice_is_refused(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = _fleet_file(tmp_path, _entry(0, 24001, 8), _entry(1, 24001, 9))
    err = _refused(capsys, tmp_path, path)
    assert "vehicles[1] (vehicle 1 (system 9, udpin:127.0.0.1:24001)): link " \
           "'udpin:127.0.0.1:24001' already used by vehicles[0]" in err  # fmt: skip


def test_an_index_the_profile_does_not_have_is_refused(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    path = _fleet_file(tmp_path, _entry(0, 24001, 8), _entry(4, 24002, 9))
    err = _refused(capsys, tmp_path, path)
    assert "vehicles[1] (vehicle 4 (system 9, udpin:127.0.0.1:24002)): index 4: profile " \
           "'field-duebendorf' has 4 vehicles (0..3)" in err  # fmt: skip


def test_indices_must_be_the_first_n_vehicles_of_the_profile(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    path = _fleet_file(tmp_path, _entry(0, 24001, 8), _entry(2, 24002, 9))
    err = _refused(capsys, tmp_path, path)
    assert "2 vehicles must be the profile's vehicles 0..1 (as --vehicles 2 flies); no entry " \
           "has index 1" in err  # fmt: skip


def test_a_file_outside_the_schema_lists_every_problem(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    path = _fleet_file(tmp_path, _entry(0, 24001, 300, colour="red"))
    err = _refused(capsys, tmp_path, path)
    assert "invalid fleet file (2 problem(s))" in err
    assert "vehicles.0.system_id: Input should be less than or equal to 255 (got 300)" in err
    assert "vehicles.0.colour: Extra inputs are not permitted" in err


def test_a_file_and_sitl_together_are_refused(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    path = _fleet_file(tmp_path, _entry(0, 24001, 8))
    err = _refused(capsys, tmp_path, path, "--sitl", "px4")
    assert "--vehicles-file and --sitl: choose one" in err


def test_a_link_that_does_not_answer_is_refused_after_the_timeout(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    port = free_udp_base(1)
    path = _fleet_file(tmp_path, _entry(0, port, 8))
    err = _refused(capsys, tmp_path, path, "--link-timeout", "1.5")
    assert (f"vehicle 0 (system 8, udpin:127.0.0.1:{port}): refused before start: no autopilot "
            f"HEARTBEAT from system 8 on udpin:127.0.0.1:{port} within 1.5 s (heard nothing)") in err  # fmt: skip


def test_a_vehicle_answering_with_another_system_id_is_refused_naming_what_was_heard(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    base = free_udp_base(1)
    with running_emulator(make_config(1, base)):
        path = _fleet_file(tmp_path, _entry(0, base, 7))
        err = _refused(capsys, tmp_path, path, "--link-timeout", "3")
    assert "no autopilot HEARTBEAT from system 7" in err
    assert "(heard systems [1])" in err


def test_another_autopilot_than_the_file_says_is_refused(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    base = free_udp_base(1)
    with running_emulator(make_config(1, base)):  # the PX4 persona
        path = _fleet_file(tmp_path, _entry(0, base, 1, autopilot="arducopter"))
        err = _refused(capsys, tmp_path, path)
    who = f"vehicle 0 (system 1, udpin:127.0.0.1:{base})"
    assert f"{who}: refused before start: the file says autopilot arducopter, its HEARTBEAT " \
           "says px4" in err  # fmt: skip


def test_an_armed_vehicle_is_refused_and_stays_as_it_was(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    base = free_udp_base(2)
    with running_emulator(make_config(2, base)):
        with Client(base + 1, 2) as pilot:  # someone armed vehicle 1 (system 2) by hand
            pilot.pump(3.0, lambda m: m.get_type() == "HEARTBEAT")
            assert pilot.command(ARM, 1.0, FORCE) == 0
        path = _fleet_file(tmp_path, _entry(0, base, 1), _entry(1, base + 1, 2))
        err = _refused(capsys, tmp_path, path)
        who = f"vehicle 1 (system 2, udpin:127.0.0.1:{base + 1})"
        assert f"{who}: refused before start: already armed" in err
        with Client(base, 1) as first:  # the fleet never armed the disarmed one
            beat = first.pump(3.0, lambda m: m.get_type() == "HEARTBEAT")
            assert beat is not None
            assert not beat.base_mode & 128


def test_sitl_for_a_profile_without_site_is_refused(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    code = main(["fleet", "--quiet", "--profile", "paper-fixed", "--sitl", "arducopter",
                 "--vehicles", "2", "--out", str(tmp_path / "run")])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2, err
    assert "--sitl: profile 'paper-fixed' has no site: SITL instances boot at the site's " \
           "WGS84 start points" in err  # fmt: skip


def test_sitl_without_a_build_is_refused_naming_the_variable(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("MDM_PX4_SITL", str(tmp_path / "nowhere"))
    code = main(["fleet", "--quiet", "--profile", "field-duebendorf", "--sitl", "mixed",
                 "--out", str(tmp_path / "run")])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2, err
    # whether this machine has an ArduCopter build or not (then the refusal names both)
    assert err.startswith("companion: --sitl: no "), err
    assert f"no px4 SITL (start-px4) in {tmp_path / 'nowhere'}; set MDM_PX4_SITL to " \
           "its folder" in err  # fmt: skip


@pytest.mark.parametrize("base", ["x", "10", "-1"])
def test_a_sitl_instance_base_outside_0_to_9_is_refused_naming_the_variable(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch, base: str
) -> None:
    monkeypatch.setenv("MDM_SITL_INSTANCE_BASE", base)
    code = main(["fleet", "--quiet", "--profile", "field-duebendorf", "--sitl", "arducopter",
                 "--vehicles", "2", "--out", str(tmp_path / "run")])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2, err
    assert f"MDM_SITL_INSTANCE_BASE={base!r}: expected an instance index 0..9" in err
    assert not list((tmp_path / "run").glob("sitl-*.log")), "an instance was started"


def test_sitl_without_either_build_is_refused_naming_both_variables(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("MDM_ARDUCOPTER_SITL", str(tmp_path / "no-ardupilot"))
    monkeypatch.setenv("MDM_PX4_SITL", str(tmp_path / "no-px4"))
    code = main(["fleet", "--quiet", "--profile", "field-duebendorf", "--sitl", "mixed",
                 "--out", str(tmp_path / "run")])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2, err
    assert err == (
        f"companion: --sitl: no arducopter SITL (start-arducopter) in {tmp_path / 'no-ardupilot'}; "
        "set MDM_ARDUCOPTER_SITL to its folder; "
        f"no px4 SITL (start-px4) in {tmp_path / 'no-px4'}; set MDM_PX4_SITL to its folder\n"
    )
