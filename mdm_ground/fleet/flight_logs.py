"""Where each vehicle's autopilot log of the flight was kept (or why not), from the
``flight_log`` records of the companions' mission logs, for the fleet's summary."""

from __future__ import annotations

from pathlib import Path

from companion.telemetry.mission_log import read_records


def flight_log_lines(out: Path, vehicles: int) -> list[str]:
    """One line per vehicle whose companion tried (vehicles on the emulator: none; it keeps no
    autopilot log and its companions exit before the landing)."""
    lines = []
    for i in range(vehicles):
        for r in read_records(out / f"mission-{i}.jsonl"):
            if r.get("event") != "flight_log":
                continue
            if r.get("path"):
                note = f" ({r['note']})" if r.get("note") else ""
                lines.append(f"  autopilot log, vehicle {i}: {r['path']} ({r['size']} bytes){note}")
            else:
                lines.append(f"  autopilot log, vehicle {i}: none: {r.get('note')}")
    return lines
