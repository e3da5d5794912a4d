"""The autopilot's own log over MAVSDK's LogFiles plugin (the same log protocol as
log_transfer.py, driven by MAVSDK): the newest entry into the run directory."""

from __future__ import annotations

import asyncio
from pathlib import Path
from typing import Any

from mavsdk.asyncio.plugins.log_files import LogFilesAsync
from mavsdk.plugins.log_files import LogFilesError, LogFilesResult

from companion.link.log_transfer import FlightLog, suffix


async def download_newest(system: Any, stem: Path, limit: float) -> FlightLog:
    """The newest log of ``system`` (MAVSDK's asyncio System) into ``stem`` + its format's
    suffix within ``limit`` wall s; MAVSDK deletes a download it cancels, so a late one is
    named, not kept."""
    files = LogFilesAsync(system)
    try:
        try:
            entries = await asyncio.wait_for(files.get_entries(), min(limit, 20.0))
        except LogFilesError as exc:
            if exc.result == LogFilesResult.NO_LOGFILES:
                return FlightLog(None, note="the vehicle holds no log")
            return FlightLog(None, note=f"MAVSDK's log list: {exc}")
        except TimeoutError:
            return FlightLog(None, note="MAVSDK's log list: no answer")
        if not entries:
            return FlightLog(None, note="the vehicle holds no log")
        entry = max(entries, key=lambda e: e.id)
        part = stem.with_suffix(".part")
        try:
            async with asyncio.timeout(limit):
                async for _ in files.download_log_file(entry, str(part)):
                    pass
        except TimeoutError:
            await files.cancel_download_log_file()
            return FlightLog(
                None, note=f"log {entry.id} ({entry.size_bytes} bytes) not down in {limit:g} s"
            )
        except LogFilesError as exc:
            return FlightLog(None, note=f"log {entry.id}: MAVSDK: {exc}")
        with part.open("rb") as f:
            head = f.read(8)
        path = part.rename(stem.with_suffix(suffix(head)))
        return FlightLog(path, path.stat().st_size)
    finally:
        files.destroy()
