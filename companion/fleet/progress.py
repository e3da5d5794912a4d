"""Live progress of a fleet from the companions' mission logs (sim time, targets, levels)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from companion.telemetry.mission_log import read_records


@dataclass
class VehicleView:
    time: float = 0.0
    level: int = 0
    phase: str = "connect"
    found: int = 0


def read_progress(log_dir: Path, vehicles: int) -> list[VehicleView]:
    """Latest time, level, phase and own confirmations of every vehicle."""
    views = []
    for i in range(vehicles):
        v = VehicleView()
        for rec in read_records(log_dir / f"mission-{i}.jsonl"):
            v.time = max(v.time, float(rec.get("t", 0.0)))
            event = rec.get("event")
            if event == "level":
                v.level = int(rec["level"])
            elif event == "phase":
                v.phase = str(rec["phase"])
            elif event == "confirmation":
                v.found += 1
        views.append(v)
    return views


def progress_line(views: list[VehicleView], team_found: int, real: int) -> str:
    """One line: sim time, targets confirmed by the team, each vehicle's level (1-based)."""
    t = max((v.time for v in views), default=0.0)
    levels = "".join(str(v.level + 1) if v.phase == "search" else v.phase[0].upper() for v in views)
    return f"t={t:7.1f} s  confirmed {team_found}/{real}  levels [{levels}]"
