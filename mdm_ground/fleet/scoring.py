"""Score a fleet run from the companions' mission logs against the profile's targets."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from companion.telemetry import events
from companion.telemetry.mission_log import read_log, read_records
from mdm_core.metrics import confirmed_within, team_times, time_to_all
from mdm_core.world import Scenario
from mdm_ground.fleet.departures import emulator_departures, team_search_start, ts_count
from mdm_ground.fleet.flight_checks import FlightCheck
from mdm_ground.fleet.outcome import ProcessEnd
from mdm_profiles import MissionProfile


@dataclass
class Confirmation:
    """One confirmation a companion logged, matched to the nearest profile target."""

    vehicle: int
    time: float
    """Seconds after that vehicle's search started."""
    north: float
    east: float
    target: int
    """Index in the profile of the target it was (-1: no target was in range)."""
    distance: float
    real: bool
    """The nearest target is real and within the confirmation radius."""


@dataclass
class FleetResult:
    """What a fleet run found, with the Monte-Carlo engine's metrics."""

    profile: str
    vehicles: int
    duration: float
    tnc: int
    """Distinct real targets confirmed within ``duration`` (T_nc)."""
    ts: float
    """Time to confirm every real target (with ``ts_rule`` confirmed_or_gone: to confirm or
    see gone, each at the earlier), capped at the profile's ts_cap."""
    ts_capped: bool
    real_targets: int
    sim_time: float
    """The latest mission time any vehicle logged (what the progress lines show), sim s."""
    search_time: float
    """The longest search a vehicle flew (its end, else its last logged time, less its search
    start), sim s."""
    first_confirmation: list[float]
    """Per target, the team's first confirmation time (inf: never)."""
    false_confirmations: int
    ts_rule: str = "confirmed"
    """The profile's mission.ts_rule: what T_S counts (fleet/departures.py)."""
    departures: list[float] = field(default_factory=list)
    """Per target, when it left the area on the mission clock (the emulator's, on which its
    path runs: ``TargetTracks.departures``), inf: not while the run lasted."""
    search_start: float | None = None
    """The team's search start on the mission clock (the earliest vehicle's), from which
    T_S counts a departure."""
    ts_confirmed: int = 0
    """Real targets T_S counted at their first confirmation."""
    ts_gone: int = 0
    """Real targets T_S counted at their departure (confirmed_or_gone: it left unconfirmed)."""
    confirmations: list[Confirmation] = field(default_factory=list)
    end_reasons: dict[int, str] = field(default_factory=dict)
    """Each vehicle's end reason from its mission log (absent: it never ended)."""
    complete: bool = False
    """The run ended by itself and every process ended normally (fleet/outcome.py): the
    figures are those of a whole mission. Set by the fleet runner."""
    stopped_by: str | None = None
    """What stopped the run early (SIGINT, SIGTERM, wall limit, the emulator), if anything."""
    ends: list[ProcessEnd] = field(default_factory=list)
    """How every companion and the emulator ended."""
    flight_checks: list[FlightCheck] = field(default_factory=list)
    """Per vehicle: its altitude layer kept, its share of search time near the fence."""
    safety_net: dict[int, dict[str, Any]] = field(default_factory=dict)
    """Per vehicle, its companion's ``safety_net`` record: the mode, and each autopilot
    parameter before and after (companion/mission/safety_net.py)."""

    def as_json(self) -> dict[str, Any]:
        out = asdict(self)
        for key in ("first_confirmation", "departures"):
            out[key] = [None if not np.isfinite(t) else t for t in getattr(self, key)]
        return out


@dataclass
class _Logged:
    """What the logs of a run hold, before the metrics."""

    per_vehicle: np.ndarray
    """(1, vehicles, targets) each vehicle's first real confirmation, s after its search
    start (inf: none)."""
    found: list[Confirmation]
    reasons: dict[int, str]
    departures: np.ndarray
    """(targets,) each target's departure, mission clock s (inf: none while the run lasted)."""


EMULATOR_EVENTS = "emulator-events.jsonl"
_SLACK_S = 2.0
"""A confirmation may be logged this long after the emulator saw the target come in range."""


@dataclass(frozen=True)
class _Truth:
    """Where a target was when it came within a vehicle's confirmation sensor (emulator log)."""

    time: float
    target: int
    position: np.ndarray


def _ground_truth(records: list[dict[str, Any]], sensor: str) -> dict[int, list[_Truth]]:
    """Per vehicle, the emulator's entered_range events of the confirmation sensor."""
    out: dict[int, list[_Truth]] = {}
    for rec in records:
        if rec.get("event") == "entered_range" and rec.get("sensor") == sensor:
            where = np.array([rec["north"], rec["east"]], dtype=float)
            out.setdefault(int(rec["vehicle"]), []).append(
                _Truth(float(rec["t"]), int(rec["target"]), where)
            )
    return out


def _match(
    where: np.ndarray, t: float, targets: np.ndarray, truth: list[_Truth] | None, drift: float
) -> tuple[int, float]:
    """The target a confirmation at ``where`` (vehicle time ``t``) was, and how far it was.

    With the emulator's log: the nearest of the targets this vehicle's confirmation sensor had
    in range up to then, less the distance such a target can have moved since (``drift`` m/s).
    Without it (fixed targets only): the nearest profile target.
    """
    if truth is None:
        gaps = np.linalg.norm(targets - where, axis=1)
        k = int(np.argmin(gaps))
        return k, float(gaps[k])
    seen = [e for e in truth if e.time <= t + _SLACK_S]
    if not seen:
        return -1, float("inf")
    gaps = [
        max(0.0, float(np.linalg.norm(e.position - where)) - drift * max(0.0, t - e.time))
        for e in seen
    ]
    best = int(np.argmin(gaps))
    return seen[best].target, gaps[best]


def _confirmations(path: Path) -> tuple[list[tuple[float, float, np.ndarray]], str | None]:
    """One vehicle's confirmations as (mission time, seconds since its search started, where
    north/east) in log order, and its last end reason (None: it never ended)."""
    logged = read_log(path)
    start = logged.search_start or 0.0
    out = [
        (e.t, e.t - start, np.array([e.event.north, e.event.east], dtype=float))
        for e in logged.events
        if isinstance(e.event, events.Confirmation)
    ]
    end = logged.end()
    return out, None if end is None else end.reason


def score(
    profile: MissionProfile,
    log_dir: Path,
    vehicles: int,
    duration: float,
    *,
    virtual_seed: int | None = None,
) -> FleetResult:
    """Read mission-<i>.jsonl of every vehicle and compute T_nc, T_S and the false confirmations.

    A confirmation counts when it lies within the confirmation radius of a real target: of the
    target's position when the emulator saw it come in range (emulator-events.jsonl in
    ``log_dir``, needed for moving targets), else of the profile's position. ``virtual_seed``:
    the companions read virtual sensors with that seed (the emulator's stayed off), so the
    targets are where that virtual world had them at the confirmation's time. Departures
    (``target_gone`` in the emulator's log, or the virtual world's own paths) count in T_S
    under ``mission.ts_rule: confirmed_or_gone`` (fleet/departures.py).
    """
    targets = np.array([[t.north, t.east] for t in profile.targets])
    real = np.array([not t.false_target for t in profile.targets])
    radius = profile.sensors[-1].radius
    emulator_log = log_dir / EMULATOR_EVENTS
    motion = profile.target_motion
    if virtual_seed is not None:
        return _score_virtual(profile, log_dir, vehicles, duration, virtual_seed)
    if motion is not None and not emulator_log.exists():
        raise FileNotFoundError(
            f"{emulator_log}: moving targets are scored against the emulator's event log, "
            "which is missing"
        )
    truth = None
    departures = np.full(len(targets), np.inf)
    if emulator_log.exists():
        records = read_records(emulator_log)
        truth = _ground_truth(records, profile.sensors[-1].name)
        departures = emulator_departures(records, len(targets), emulator_log)
    drift = 0.0 if motion is None else motion.speed * max(abs(motion.low), abs(motion.high))
    per_vehicle = np.full((1, vehicles, len(targets)), np.inf)
    found: list[Confirmation] = []
    reasons: dict[int, str] = {}
    for i in range(vehicles):
        mine = None if truth is None else truth.get(i, [])
        confirmed, reason = _confirmations(log_dir / f"mission-{i}.jsonl")
        if reason is not None:
            reasons[i] = reason
        for at, t, where in confirmed:
            k, gap = _match(where, at, targets, mine, drift * np.sqrt(2.0))
            ok = bool(k >= 0 and real[k] and gap <= radius)
            found.append(Confirmation(i, t, float(where[0]), float(where[1]), k, gap, ok))
            if ok:
                per_vehicle[0, i, k] = min(per_vehicle[0, i, k], t)
    return _result(profile, log_dir, duration, _Logged(per_vehicle, found, reasons, departures))


def safety_nets(log_dir: Path, vehicles: int) -> dict[int, dict[str, Any]]:
    """Each vehicle's latest ``safety_net`` record (a restarted companion writes none: its
    vehicle was armed already), without the record's own keys."""
    out: dict[int, dict[str, Any]] = {}
    for i in range(vehicles):
        path = log_dir / f"mission-{i}.jsonl"
        nets = [r for r in read_records(path) if r.get("event") == "safety_net"]
        if nets:
            out[i] = {k: v for k, v in nets[-1].items() if k not in ("event", "t")}
    return out


def flown_times(log_dir: Path, vehicles: int) -> tuple[float, float]:
    """The latest mission time logged and the longest search flown (end, else last record,
    less the search start), sim s."""
    sim_time = search_time = 0.0
    for i in range(vehicles):
        logged = read_log(log_dir / f"mission-{i}.jsonl")
        last, start = logged.last_time, logged.search_start
        ends = [e.t for e in logged.events if isinstance(e.event, events.End)]
        end = ends[-1] if ends else None
        sim_time = max(sim_time, last)
        if start is not None:
            search_time = max(search_time, (last if end is None else end) - start)
    return round(sim_time, 3), round(search_time, 3)


def _result(
    profile: MissionProfile, log_dir: Path, duration: float, logged: _Logged
) -> FleetResult:
    real = np.array([not t.false_target for t in profile.targets])
    vehicles = logged.per_vehicle.shape[1]
    times = team_times(logged.per_vehicle)
    tnc = int(confirmed_within(times, duration)[0])
    rule = profile.mission.ts_rule
    start = team_search_start(log_dir, vehicles)
    counted = ts_count(times[0], logged.departures, start, real, rule)
    ts, capped = time_to_all(times, real, profile.mission.ts_cap, counted.gone[None, :])
    sim_time, search_time = flown_times(log_dir, vehicles)
    return FleetResult(
        profile=profile.name,
        vehicles=vehicles,
        duration=duration,
        tnc=tnc,
        ts=float(ts[0]),
        ts_capped=bool(capped[0]),
        real_targets=int(real.sum()),
        sim_time=sim_time,
        search_time=search_time,
        first_confirmation=[float(x) for x in times[0]],
        false_confirmations=sum(not c.real for c in logged.found),
        ts_rule=rule,
        departures=[float(x) for x in logged.departures],
        search_start=start,
        ts_confirmed=counted.confirmed,
        ts_gone=counted.departed,
        confirmations=logged.found,
        end_reasons=logged.reasons,
        safety_net=safety_nets(log_dir, vehicles),
    )


def _score_virtual(
    profile: MissionProfile, log_dir: Path, vehicles: int, duration: float, seed: int
) -> FleetResult:
    """:func:`score` against the virtual sensors' own targets (exact: same seed, same world)."""
    scenario = Scenario.from_profile(profile)
    _, tracks = scenario.live_run(seed, profile.fleet.vehicles, profile.fleet.start)
    run = np.zeros(1, dtype=np.intp)
    real = ~scenario.targets.false_mask
    radius = profile.sensors[-1].radius
    per_vehicle = np.full((1, vehicles, scenario.targets.count), np.inf)
    found: list[Confirmation] = []
    reasons: dict[int, str] = {}
    for i in range(vehicles):
        confirmed, reason = _confirmations(log_dir / f"mission-{i}.jsonl")
        if reason is not None:
            reasons[i] = reason
        for at, t, where in confirmed:
            gaps = np.linalg.norm(tracks.positions(run, np.array([at]))[0] - where, axis=1)
            k = int(np.argmin(gaps))
            ok = bool(real[k] and gaps[k] <= radius)
            found.append(
                Confirmation(i, t, float(where[0]), float(where[1]), k, float(gaps[k]), ok)
            )
            if ok:
                per_vehicle[0, i, k] = min(per_vehicle[0, i, k], t)
    # the virtual world's own departures, up to the last time the run logged
    departures = tracks.departures(flown_times(log_dir, vehicles)[0])[0]
    return _result(profile, log_dir, duration, _Logged(per_vehicle, found, reasons, departures))
