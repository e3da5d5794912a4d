"""The page's event log: what happened, one line each (mission time, vehicle, what), from the
companions' events, the page's commands and their answers, and the vehicles' MQTT status.

Pure: the caller gives the times. The newest LOG_KEPT entries are kept; each has a number
(its place in the whole log) so that a page is sent each entry once."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Any

LOG_KEPT = 5000
"""Entries kept for the page (the mission logs on disk keep everything)."""
_QUIET = frozenset({"tick", "latency", "frame"})
"""Records too frequent or too technical for the log (in the mission log still)."""
_ALERT_STATES = frozenset({"lost", "breach", "failed", "mismatch", "silent", "outside"})


@dataclass(frozen=True)
class LogEntry:
    """One line of the log."""

    n: int
    """Its number in the whole log (0, 1, ...)."""
    t: float | None
    """Mission time (vehicle s) of the vehicle that reported it; None for the page's own."""
    vehicle: int | None
    """None: every vehicle (a command to all) or the page itself."""
    kind: str
    """The event (``confirmation``, ``command``, ...) or ``sent`` / ``status`` for the page's."""
    text: str
    severity: str
    """``info``, ``good`` (a confirmation) or ``alert`` (failsafes, refusals, breaches)."""

    def as_json(self) -> dict[str, Any]:
        return {
            "n": self.n, "t": self.t, "vehicle": self.vehicle, "kind": self.kind,
            "text": self.text, "severity": self.severity,
        }  # fmt: skip


class EventLog:
    """The newest LOG_KEPT entries."""

    def __init__(self, kept: int = LOG_KEPT) -> None:
        self.entries: deque[LogEntry] = deque(maxlen=kept)
        self.total = 0
        """Entries ever added (the next one's number)."""

    def add(
        self, t: float | None, vehicle: int | None, kind: str, text: str, severity: str
    ) -> None:
        self.entries.append(LogEntry(self.total, t, vehicle, kind, text, severity))
        self.total += 1

    def record(self, vehicle: int, record: dict[str, Any]) -> None:
        """A companion's event (an MQTT ``event`` or a mission-log line), if worth a line."""
        kind = record.get("event")
        if not isinstance(kind, str) or kind in _QUIET:
            return
        t = record.get("t")
        when = float(t) if isinstance(t, int | float) and not isinstance(t, bool) else None
        text, severity = describe(kind, record)
        self.add(when, vehicle, kind, text, severity)

    def since(self, n: int) -> list[LogEntry]:
        """The entries numbered ``n`` and later that are still kept."""
        first = self.total - len(self.entries)
        return list(self.entries)[max(0, n - first) :]


def describe(kind: str, r: dict[str, Any]) -> tuple[str, str]:
    """One line of text for a record, and its severity."""
    where = _where(r)
    level = r.get("level")
    shown_level = f"level {level + 1}" if isinstance(level, int) else "level ?"
    if kind == "detection":
        return f"detection{where}, {shown_level}", "info"
    if kind == "confirmation":
        return f"confirmation{where} ({r.get('found', '?')} found)", "good"
    if kind == "level":
        return f"{shown_level} (sensor {r.get('sensor', '?')})", "info"
    if kind == "fallback":
        return f"fell back to {shown_level}", "info"
    if kind == "phase":
        by = f" by {r['by']}" if isinstance(r.get("by"), str) else ""
        return f"phase {r.get('phase')}{by}", "info"
    if kind == "mode":
        return f"mode {r.get('mode')}" + ("" if r.get("guided") else " (not guided)"), "info"
    if kind == "link":
        silent = r.get("silent")
        after = f" after {silent:.1f} s silent" if isinstance(silent, int | float) else ""
        state = str(r.get("state"))
        return f"autopilot link {state}{after}", "alert" if state == "lost" else "info"
    if kind == "end":
        return f"mission end: {r.get('reason')} ({r.get('found', '?')} found)", "info"
    if kind == "exit":
        status = r.get("status")
        return f"companion exit {status}: {r.get('cause')}", "info" if status == 0 else "alert"
    if kind == "command":
        return f"command {r.get('command')} accepted (id {r.get('id')})", "info"
    if kind == "error":
        return f"{r.get('source')} refused: {r.get('error')}", "alert"
    if kind == "fence":
        return f"fence {r.get('state')}{where}", "alert"
    rest = ", ".join(f"{k} {v}" for k, v in r.items() if k not in ("event", "seq", "vehicle", "t"))
    alert = kind in ("refused", "setpoint_refused", "telemetry_dropped") or (
        r.get("state") in _ALERT_STATES
    )
    return f"{kind.replace('_', ' ')}: {rest}" if rest else kind, "alert" if alert else "info"


def _where(r: dict[str, Any]) -> str:
    n, e = r.get("north"), r.get("east")
    if isinstance(n, int | float) and isinstance(e, int | float):
        return f" at N {n:.0f} E {e:.0f}"
    return ""
