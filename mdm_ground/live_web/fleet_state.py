"""What the page shows, built from the companions' MQTT messages or mission-log records.

Pure: no sockets or clocks; the caller passes the wall time a message arrived (``wall``) and
the time a snapshot is taken.
"""

from __future__ import annotations

import json
import math
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mdm_ground.live_web.event_log import EventLog
from mdm_profiles import MissionProfile

TRACK_STEP_M = 5.0
"""A track point is kept when the vehicle has moved this far from the last one kept."""
TRACK_KEPT = 2000
"""Track points kept per vehicle, the newest (10 km of flight at TRACK_STEP_M): the page's
history is bounded, the mission log on disk has the whole flight."""
ACKS_KEPT = 50
"""Command outcomes the page lists (newest first)."""


def _number(value: Any) -> float | None:
    """A finite number from a payload field, else None (bools are not numbers here)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value) if math.isfinite(value) else None


@dataclass
class VehicleState:
    """One vehicle as last heard."""

    vehicle: int
    t: float = 0.0
    north: float | None = None
    east: float | None = None
    alt: float | None = None
    mode: str | None = None
    armed: bool | None = None
    phase: str | None = None
    level: int | None = None
    ci: float | None = None
    found: int = 0
    battery: float | None = None
    heard: float | None = None
    """Wall time of the last message from it."""
    online: bool | None = None
    """Its retained MQTT status (None: not heard)."""
    end: str | None = None
    sensor: int | None = None
    """The index of the sensor switched on (its level's)."""
    stale: bool = False
    """Shown stale at the last snapshot (its change goes to the event log)."""
    track: list[tuple[float, float]] = field(default_factory=list)
    """The newest TRACK_KEPT points (up to twice that before old ones are dropped)."""
    track_base: int = 0
    """The number of ``track[0]`` among every point this vehicle has had."""

    def move_to(self, north: float, east: float) -> None:
        self.north, self.east = round(north, 1), round(east, 1)
        if not self.track or math.dist(self.track[-1], (north, east)) >= TRACK_STEP_M:
            self.track.append((self.north, self.east))
            if len(self.track) >= 2 * TRACK_KEPT:  # dropped in blocks: not a copy per point
                del self.track[:TRACK_KEPT]
                self.track_base += TRACK_KEPT

    @property
    def track_end(self) -> int:
        """The number of points this vehicle has had (the next one's number)."""
        return self.track_base + len(self.track)


@dataclass(frozen=True)
class Mark:
    """A detection or confirmation where the vehicle reported it."""

    vehicle: int
    t: float
    north: float
    east: float
    level: int


@dataclass
class Sent:
    """What one page already holds: each vehicle's track points and the log entries, by
    number (the next snapshot sends what comes after)."""

    tracks: dict[int, int] = field(default_factory=dict)
    log: int = 0


@dataclass
class CommandOutcome:
    """What became of one command the page sent, per vehicle that answered."""

    id: str
    command: str
    target: str
    """``uav<i>`` or ``all``."""
    sent: float
    answers: dict[int, str] = field(default_factory=dict)
    """Vehicle -> ``accepted`` or ``refused: <reason>``."""
    error: str | None = None
    """Why the broker did not take it (nothing was sent)."""


class FleetState:
    """The team as the page shows it."""

    def __init__(self, profile: MissionProfile, *, show_targets: bool, stale_after: float) -> None:
        self.profile = profile
        self.show_targets = show_targets
        self.stale_after = stale_after
        self.vehicles: dict[int, VehicleState] = {}
        self.detections: list[Mark] = []
        self.confirmations: list[Mark] = []
        self.commands: deque[CommandOutcome] = deque(maxlen=ACKS_KEPT)
        self.log = EventLog()
        real = [t for t in profile.targets if not t.false_target]
        self._real = np.array([[t.north, t.east] for t in real], dtype=float).reshape(-1, 2)
        self._radius = profile.sensors[-1].radius

    def vehicle(self, i: int) -> VehicleState:
        if i not in self.vehicles:
            self.vehicles[i] = VehicleState(i)
        return self.vehicles[i]

    # -- input -----------------------------------------------------------------------------

    def on_state(self, i: int, payload: dict[str, Any], wall: float) -> None:
        """A ``state`` message (docs/mqtt.md); fields that are missing or not finite are kept
        as they were."""
        v = self.vehicle(i)
        v.heard = wall
        t = _number(payload.get("t"))
        v.t = max(v.t, t) if t is not None else v.t
        north, east = _number(payload.get("north")), _number(payload.get("east"))
        if north is not None and east is not None:
            v.move_to(north, east)
        alt = _number(payload.get("alt"))
        v.alt = v.alt if alt is None else round(alt, 1)
        for key in ("mode", "phase"):
            value = payload.get(key)
            if isinstance(value, str):
                setattr(v, key, value[:32])
        if isinstance(payload.get("armed"), bool):
            v.armed = payload["armed"]
        for key in ("level", "sensor"):
            value = payload.get(key)
            if isinstance(value, int) and not isinstance(value, bool):
                setattr(v, key, value)
        if "ci" in payload:  # null on level 0: no index there
            v.ci = _number(payload["ci"])
        battery = _number(payload.get("battery"))
        v.battery = v.battery if battery is None else battery
        found = payload.get("found")
        if isinstance(found, int) and not isinstance(found, bool):
            v.found = found

    def on_status(self, i: int, payload: dict[str, Any], wall: float) -> None:
        """A retained ``status`` message: online or offline."""
        v = self.vehicle(i)
        online = payload.get("state") == "online"
        if online != v.online:
            if online:
                self.log.add(v.t, i, "status", "companion online (MQTT)", "info")
            elif payload.get("clean") is False:
                text = "companion gone without a goodbye (the broker's last will)"
                self.log.add(v.t, i, "status", text, "alert")
            else:
                self.log.add(v.t, i, "status", "companion offline (it ended)", "info")
        v.online = online
        if v.online:
            v.heard = wall

    def on_event(self, i: int, record: dict[str, Any], wall: float | None) -> None:
        """A mission-log record (an MQTT ``event``, or a line of ``mission-I.jsonl``)."""
        v = self.vehicle(i)
        if wall is not None:
            v.heard = wall
        t = _number(record.get("t")) or 0.0
        v.t = max(v.t, t)
        kind = record.get("event")
        if kind == "tick":
            self.on_state(
                i,
                {
                    k: record[k]
                    for k in ("north", "east", "alt", "phase", "level", "found")
                    if k in record
                },
                v.heard or 0.0,
            )
        elif kind == "phase" and isinstance(record.get("phase"), str):
            v.phase = record["phase"]
        elif kind == "mode" and isinstance(record.get("mode"), str):
            v.mode = record["mode"]
        elif kind == "level" and isinstance(record.get("level"), int):
            v.level = record["level"]
            if isinstance(record.get("sensor"), int):
                v.sensor = record["sensor"]
        elif kind in ("detection", "confirmation"):
            north, east = _number(record.get("north")), _number(record.get("east"))
            level = record.get("level")
            if north is None or east is None or not isinstance(level, int):
                return
            mark = Mark(i, t, north, east, level)
            (self.detections if kind == "detection" else self.confirmations).append(mark)
            if kind == "confirmation":
                v.found += 1
        elif kind == "end" and isinstance(record.get("reason"), str):
            v.end = record["reason"]
        elif kind == "command":
            self._answer(i, record.get("id"), "accepted")
        elif kind == "error" and record.get("source") == "command":
            self._answer(i, _payload_id(record.get("payload")), f"refused: {record.get('error')}")
        self.log.record(i, record)

    def on_armed(self, i: int, armed: bool, t: float) -> None:
        """The emulator's ``armed`` / ``disarmed`` event (replays)."""
        self.vehicle(i).armed = armed
        self.log.add(t, i, "armed", "armed (emulator)" if armed else "disarmed (emulator)", "info")

    def clock(self) -> float:
        """The mission clock: the latest mission time any vehicle reported."""
        return max((v.t for v in self.vehicles.values()), default=0.0)

    def sent(self, outcome: CommandOutcome) -> None:
        """A command the page publishes now."""
        self.commands.appendleft(outcome)
        vehicle = None if outcome.target == "all" else int(outcome.target.removeprefix("uav"))
        text = f"operator sent {outcome.command} to {outcome.target} (id {outcome.id})"
        self.log.add(round(self.clock(), 1), vehicle, "sent", text, "info")

    def not_sent(self, outcome: CommandOutcome, error: str) -> None:
        """The broker did not take ``outcome``'s command."""
        outcome.error = f"not sent: {error}"
        vehicle = None if outcome.target == "all" else int(outcome.target.removeprefix("uav"))
        text = f"{outcome.command} to {outcome.target} not sent: {error}"
        self.log.add(round(self.clock(), 1), vehicle, "sent", text, "alert")

    def _answer(self, i: int, ref: Any, answer: str) -> None:
        for c in self.commands:
            if c.id == ref:
                # a refusal follows the command's acceptance event: it wins
                if answer != "accepted" or i not in c.answers:
                    c.answers[i] = answer
                return

    # -- output ----------------------------------------------------------------------------

    def tnc(self) -> int:
        """Real profile targets with a confirmation within the confirmation sensor's radius
        (the live figure; the fleet's results.json matches against the emulator's truth)."""
        if not self.confirmations or not len(self._real):
            return 0
        where = np.array([[c.north, c.east] for c in self.confirmations])
        gaps = np.linalg.norm(self._real[:, None, :] - where[None, :, :], axis=2)
        return int((gaps.min(axis=1) <= self._radius).sum())

    def snapshot(self, now: float, sent: Sent | None = None) -> dict[str, Any]:
        """Everything the page draws; each vehicle's track and the log only from what ``sent``
        says the page holds (updated: what it holds once it has this one)."""
        sent = Sent() if sent is None else sent
        vehicles = []
        for i in sorted(self.vehicles):
            v = self.vehicles[i]
            start = max(sent.tracks.get(i, 0), v.track_base)
            sent.tracks[i] = v.track_end
            age = None if v.heard is None else max(0.0, now - v.heard)
            stale = math.isfinite(self.stale_after) and (
                v.online is False or age is None or age > self.stale_after
            )
            if stale != v.stale and v.online is not False and age is not None:
                text = f"silent for {age:.0f} s (stale)" if stale else "heard again"
                self.log.add(v.t, i, "stale", text, "alert" if stale else "info")
            v.stale = stale
            vehicles.append(
                {
                    "vehicle": i,
                    "t": round(v.t, 1),
                    "north": v.north,
                    "east": v.east,
                    "alt": v.alt,
                    "mode": v.mode,
                    "armed": v.armed,
                    "phase": v.phase,
                    "level": v.level,
                    "ci": v.ci,
                    "found": v.found,
                    "battery": v.battery,
                    "age": None if age is None else round(age, 1),
                    "online": v.online,
                    "stale": stale,
                    "end": v.end,
                    "sensor": v.sensor,
                    "track_from": start,
                    "track": v.track[start - v.track_base :],
                }
            )
        log = self.log.since(sent.log)
        sent.log = self.log.total
        return {
            "type": "snapshot",
            "clock": round(self.clock(), 1),
            "tnc": self.tnc(),
            "vehicles": vehicles,
            "detections": [_mark(m) for m in self.detections],
            "confirmations": [_mark(m) for m in self.confirmations],
            "commands": [
                {
                    "id": c.id,
                    "command": c.command,
                    "target": c.target,
                    "error": c.error,
                    "answers": {str(k): a for k, a in sorted(c.answers.items())},
                }
                for c in self.commands
            ],
            "log": [e.as_json() for e in log],
        }


def _mark(m: Mark) -> dict[str, Any]:
    return {"vehicle": m.vehicle, "t": m.t, "north": m.north, "east": m.east, "level": m.level}


def _payload_id(payload: Any) -> str | None:
    """The ``id`` of a refused command's payload (as echoed in the ``error`` event)."""
    if not isinstance(payload, str):
        return None
    try:
        data = json.loads(payload)
    except json.JSONDecodeError:
        return None
    ref = data.get("id") if isinstance(data, dict) else None
    return None if ref is None else str(ref)
