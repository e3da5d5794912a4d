"""Live progress of a fleet from the companions' mission logs (sim time, targets, levels) and
which vehicles are still in the air (the emulator's event log)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from companion.mission.phase import Phase
from companion.telemetry import events
from companion.telemetry.mission_log import read_log, read_records
from mdm_ground.fleet.scoring import EMULATOR_EVENTS

LETTERS = {
    Phase.CONNECT.value: "C",
    Phase.PREPARE.value: "P",
    Phase.CLIMB.value: "T",
    Phase.PAUSED.value: "H",
    Phase.LINK_LOST.value: "L",
    Phase.RETURN.value: "R",
    Phase.DONE.value: "D",
}
"""One letter per phase other than the search (which shows the level)."""
FAILED = "X"
LEGEND = (
    "levels: 1-9 searching at that level; C connecting, P preparing (mode, arming), "
    "T taking off, H held (paused), L link lost, R flying the end action, D done, "
    f"{FAILED} companion exited with an error"
)


@dataclass
class VehicleView:
    time: float = 0.0
    level: int = 0
    phase: str = Phase.CONNECT.value
    found: int = 0
    failed: bool = False
    """Its companion exited with an error (set by the fleet runner)."""

    def letter(self) -> str:
        if self.failed:
            return FAILED
        if self.phase == Phase.SEARCH.value:
            return str(self.level + 1)
        return LETTERS.get(self.phase, "?")


def read_progress(log_dir: Path, vehicles: int) -> list[VehicleView]:
    """Latest time, level, phase and own confirmations of every vehicle."""
    views = []
    for i in range(vehicles):
        logged = read_log(log_dir / f"mission-{i}.jsonl")
        v = VehicleView(time=logged.last_time, found=len(logged.confirmed))
        for e in logged.events:
            if isinstance(e.event, events.Level):
                v.level = e.event.level
            elif isinstance(e.event, events.PhaseChange):
                v.phase = e.event.phase
        views.append(v)
    return views


def progress_line(
    views: list[VehicleView], team_found: int, real: int, gone: int | None = None
) -> str:
    """One line: sim time, targets confirmed by the team (and, where T_S counts departures,
    the real targets gone unconfirmed), each vehicle's level or phase letter."""
    t = max((v.time for v in views), default=0.0)
    letters = "".join(v.letter() for v in views)
    left = "" if gone is None else f"  gone {gone}"
    return f"sim t={t:7.1f} s  confirmed {team_found}/{real}{left}  levels [{letters}]"


def airborne(log_dir: Path) -> list[int]:
    """Vehicles the emulator last logged as armed (they have not landed and disarmed)."""
    armed: dict[int, bool] = {}
    for rec in read_records(log_dir / EMULATOR_EVENTS):
        if rec.get("event") in ("armed", "disarmed"):
            armed[int(rec["vehicle"])] = rec["event"] == "armed"
    return sorted(i for i, up in armed.items() if up)


def operator_ended(log_dir: Path, vehicles: int) -> list[int]:
    """Vehicles whose mission an operator's command ended (MQTT land or abort)."""
    out = []
    for i in range(vehicles):
        end = read_log(log_dir / f"mission-{i}.jsonl").end()
        if end is not None and end.reason.startswith("operator "):
            out.append(i)
    return out
