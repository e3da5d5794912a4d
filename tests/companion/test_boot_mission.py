"""The service's per-boot mission rule (`companion run --new-mission-per-boot`): a restart in
the same boot and a reboot mid-mission keep the run directory (its resume rules apply); only a
mission that ended in an earlier boot is moved aside so that this boot flies a new one."""

from __future__ import annotations

from pathlib import Path

from companion.service.boot_mission import ENDED, begin_boot_mission
from companion.telemetry import MissionLog


def _boot(tmp_path: Path, boot: str) -> Path:
    path = tmp_path / "boot_id"
    path.write_text(boot + "\n")
    return path


def _mission(run: Path, *, ended: bool) -> None:
    log = MissionLog(run / "mission-0.jsonl")
    log.emit(0.0, "start", vehicle=0, profile="paper-fixed", seed=0, resumed=0, altitude=30.0)
    if ended:
        log.emit(50.0, "end", reason="mission time", found=0)
    log.close()
    (run / "vehicle-0.tlog").write_bytes(b"\0" * 8)


def test_a_restart_in_the_same_boot_keeps_an_ended_mission(tmp_path: Path) -> None:
    run = tmp_path / "run"
    assert begin_boot_mission(run, 0, boot_id=_boot(tmp_path, "a")) is None
    _mission(run, ended=True)
    assert begin_boot_mission(run, 0, boot_id=_boot(tmp_path, "a")) is None
    assert (run / "mission-0.jsonl").exists()  # read again: "already ended", nothing flown


def test_a_reboot_mid_mission_keeps_it(tmp_path: Path) -> None:
    run = tmp_path / "run"
    begin_boot_mission(run, 0, boot_id=_boot(tmp_path, "a"))
    _mission(run, ended=False)
    assert begin_boot_mission(run, 0, boot_id=_boot(tmp_path, "b")) is None
    assert (run / "mission-0.jsonl").exists()
    assert (run / "boot-id").read_text().strip() == "b"


def test_an_ended_mission_of_an_earlier_boot_is_moved_aside(tmp_path: Path) -> None:
    run = tmp_path / "run"
    begin_boot_mission(run, 0, boot_id=_boot(tmp_path, "a"))
    _mission(run, ended=True)
    moved = begin_boot_mission(run, 0, boot_id=_boot(tmp_path, "b"))
    assert moved is not None
    assert moved.parent == run / ENDED
    assert sorted(p.name for p in moved.iterdir()) == ["mission-0.jsonl", "vehicle-0.tlog"]
    assert sorted(p.name for p in run.iterdir()) == ["boot-id", ENDED]
    assert begin_boot_mission(run, 0, boot_id=_boot(tmp_path, "b")) is None  # once only


def test_a_first_start_without_a_marker_moves_an_ended_mission(tmp_path: Path) -> None:
    """A run directory the unit did not start before (no boot-id): an ended mission there is
    not this boot's, so it is moved aside too."""
    run = tmp_path / "run"
    run.mkdir()
    _mission(run, ended=True)
    assert begin_boot_mission(run, 0, boot_id=_boot(tmp_path, "a")) is not None
