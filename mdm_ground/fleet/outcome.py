"""How each process of a fleet run ended: from its exit status, mission log and output."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from companion.telemetry.events import Exit
from companion.telemetry.mission_log import read_log, read_records

NORMAL_ENDS = frozenset({"mission time", "all targets", "operator abort", "operator land"})
"""End reasons of a mission flown as asked: its time, every target, or an operator's MQTT
command. Anything else (climb timeout, battery, a stop signal, no end at all) is not normal."""
_LEVEL = re.compile(r"\b(ERROR|CRITICAL)\b")
_MAX_LINE = 200


@dataclass(frozen=True)
class ProcessEnd:
    """One process of the run: how it ended, the first error it wrote, where its output is."""

    name: str
    """``vehicle I`` or ``emulator``."""
    how: str
    """The mission's end reason (vehicles), else what the process did."""
    exit_code: int | None
    """None: not started in this run (resumed runs: it ended earlier)."""
    error: str | None
    log: str
    ok: bool
    strays: tuple[str, ...] = ()
    """Other senders with this vehicle's system id that its companion ignored (address: the
    one it locked to), from the mission log's ``stray`` records."""


def first_error(path: Path) -> str | None:
    """The first error a process wrote: a traceback's exception line, an ERROR log line, or the
    CLI's own refusal (``companion: ...``, ``sim-vehicle: ...``)."""
    try:
        lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError:
        return None
    for k, line in enumerate(lines):
        if line.startswith("Traceback"):
            cause = next((r for r in lines[k + 1 :] if r and not r[0].isspace()), line)
            return cause.strip()[:_MAX_LINE]
        level = _LEVEL.search(line)
        if level is not None:
            return line[level.start() :].strip()[:_MAX_LINE]
        if line.startswith(("companion:", "sim-vehicle:")):
            return line.strip()[:_MAX_LINE]
    return None


def vehicle_end(out: Path, vehicle: int, exit_code: int | None, earlier: str | None) -> ProcessEnd:
    """How vehicle ``vehicle``'s companion ended (``earlier``: it ended in an earlier run)."""
    log = out / f"companion-{vehicle}.log"
    path = out / f"mission-{vehicle}.jsonl"
    logged = read_log(path)
    end = logged.end()
    reason = None if end is None else end.reason
    exits = logged.of(Exit)
    if reason is not None and exits and exits[-1].status != 0:  # how the vehicle was left
        cause = exits[-1].cause
        reason = cause if cause.startswith(reason) else f"{reason}: {cause}"
    strays = tuple(
        f"{r.get('address')} (locked to {r.get('locked')})"
        for r in read_records(path)
        if r.get("event") == "stray"
    )
    if exit_code is None:
        how = f"{earlier or reason} (earlier run)"
        ok = (earlier or reason) in NORMAL_ENDS
    elif reason is None:
        how = "no end in its mission log" + exit_words(exit_code)
        ok = False
    else:
        how = reason + exit_words(exit_code)
        ok = exit_code == 0 and reason in NORMAL_ENDS
    return ProcessEnd(f"vehicle {vehicle}", how, exit_code, first_error(log), str(log), ok, strays)


def emulator_end(out: Path, exit_code: int | None, exited_early: bool) -> ProcessEnd:
    """The emulator is fine when it ran until the fleet stopped it and then exited cleanly."""
    log = out / "emulator.log"
    if exited_early:
        how = f"exited on its own before the companions ended{exit_words(exit_code)}"
    else:
        how = "stopped by the fleet" + exit_words(exit_code)
    ok = not exited_early and exit_code == 0
    return ProcessEnd("emulator", how, exit_code, first_error(log), str(log), ok)


def exit_words(code: int | None) -> str:
    if code is None or code == 0:
        return ""
    if code < 0:
        return f", killed by signal {-code}"
    return f", exit code {code}"
