"""`companion run --new-mission-per-boot` (what `companion service`'s unit runs): which mission
a start of the service flies, decided from the run directory and the machine's boot id.

- A mission written in this boot (the service restarted after a crash) is kept: the restarted
  companion reads its mission log and follows its resume rules (an ended mission stays ended, a
  begun search goes on), never taking a vehicle in flight back as a new mission.
- A mission of an earlier boot that did not end is kept too: the companion's computer rebooted
  mid-mission (a brown-out in the air) and the mission goes on by the same rules.
- A mission of an earlier boot that ended is moved into ``ended/<boot time>/`` of the run
  directory: the vehicle was powered up again for a new flight, and this boot flies a new one.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path

from companion.telemetry import read_log

log = logging.getLogger(__name__)

BOOT_ID = Path("/proc/sys/kernel/random/boot_id")
"""The kernel's id of this boot (a new random UUID at every boot)."""
MARKER = "boot-id"
"""The file of the run directory that holds the id of the boot that last started in it."""
ENDED = "ended"
"""The folder of the run directory that ended missions of earlier boots are moved into."""


def begin_boot_mission(log_dir: Path, vehicle: int, *, boot_id: Path = BOOT_ID) -> Path | None:
    """Decide, as the module says, before anything opens a file of ``log_dir``; where an ended
    mission of an earlier boot was moved to, or None where the run directory is kept."""
    log_dir.mkdir(parents=True, exist_ok=True)
    current = boot_id.read_text().strip()
    marker = log_dir / MARKER
    previous = marker.read_text().strip() if marker.exists() else None
    moved: Path | None = None
    mission_log = log_dir / f"mission-{vehicle}.jsonl"
    if previous != current and mission_log.exists() and read_log(mission_log).ended:
        stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime(mission_log.stat().st_mtime))
        moved = log_dir / ENDED / stamp
        moved.mkdir(parents=True, exist_ok=True)
        for entry in sorted(log_dir.iterdir()):
            if entry.name not in (ENDED, MARKER):
                entry.rename(moved / entry.name)
        log.info("the mission of an earlier boot had ended: moved to %s; a new mission", moved)
    elif mission_log.exists():
        why = "this boot's (a restart)" if previous == current else "not ended (a reboot)"
        log.info("mission log %s is %s: its resume rules apply", mission_log, why)
    marker.write_text(current + "\n")
    return moved
