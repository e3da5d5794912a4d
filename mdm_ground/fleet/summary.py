"""The screen summary of a fleet run and its exit status."""

from __future__ import annotations

import math
import signal
from pathlib import Path

from mdm_ground.fleet.flight_checks import NEAR_FENCE_M
from mdm_ground.fleet.flight_logs import flight_log_lines
from mdm_ground.fleet.outcome import ProcessEnd
from mdm_ground.fleet.scoring import FleetResult

EXIT_FAILED = 1
"""A process did not end normally, or the run was stopped by its wall limit."""


def exit_status(result: FleetResult) -> int:
    """0 only for a complete run; 128 + the signal for a run stopped by SIGINT/SIGTERM."""
    if result.complete:
        return 0
    if result.stopped_by in ("SIGINT", "SIGTERM"):
        return 128 + int(signal.Signals[result.stopped_by])
    return EXIT_FAILED


def _ts_words(r: FleetResult) -> str:
    gone = r.ts_rule == "confirmed_or_gone"
    if not r.ts_capped:
        split = f" ({r.ts_confirmed} confirmed, {r.ts_gone} gone)" if gone else ""
        return f"{r.ts:.1f} s{split}"
    ever = sum(1 for t in r.first_confirmation if math.isfinite(t))
    done = f"{r.ts_confirmed} confirmed and {r.ts_gone} gone" if gone else f"{ever} confirmed"
    return (
        f"not reached: {done} of {r.real_targets} real targets in "
        f"{r.search_time:.1f} s of search (results.json counts it as the profile's ts_cap, "
        f"{r.ts:.0f} s, as the Monte-Carlo tables do)"
    )


def _departure_lines(r: FleetResult) -> list[str]:
    """One line per target that left the area, on the mission clock and after the search
    start (what confirmed_or_gone counts)."""
    lines = []
    for k, left in enumerate(r.departures):
        if not math.isfinite(left):
            continue
        after = "" if r.search_start is None else f", {left - r.search_start:.1f} s into the search"
        lines.append(f"    target T{k + 1} left the area at mission time {left:.1f} s{after}")
    return lines


def _table(ends: list[ProcessEnd]) -> list[str]:
    how = max(len("how it ended"), *(len(e.how) for e in ends))
    error = max(len("first error"), *(len(e.error or "-") for e in ends))
    rows = [f"    {'who':<11} {'how it ended':<{how}}  {'first error':<{error}}  log"]
    rows += [f"    {e.name:<11} {e.how:<{how}}  {e.error or '-':<{error}}  {e.log}" for e in ends]
    return rows


def _check_lines(r: FleetResult) -> list[str]:
    """Each vehicle's share of search time near the fence; any vehicle that left its layer."""
    shares = [(c.vehicle, c.near_fence) for c in r.flight_checks if c.near_fence is not None]
    lines = []
    if shares:
        each = ", ".join(f"{i}: {share:.0%}" for i, share in shares)
        lines.append(f"  search time within {NEAR_FENCE_M:g} m of the fence, per vehicle: {each}")
    lines += [f"  LAYER: {p}" for c in r.flight_checks if (p := c.problem()) is not None]
    return lines


def summary_lines(r: FleetResult, out: Path, wall: float) -> list[str]:
    """What the run found and how every process ended, as printed after the run."""
    searched = (
        f"searched {r.search_time:.1f} of {r.duration:g} sim s asked"
        if r.search_time > 0
        else f"no vehicle started its search ({r.duration:g} sim s asked)"
    )
    lines = [
        f"{r.profile}: {r.vehicles} vehicles; {searched}; mission clock {r.sim_time:.1f} s "
        f"(take-off included); {wall:.1f} s wall",
        f"  targets confirmed within {r.duration:g} s (T_nc): {r.tnc} of {r.real_targets} real",
        f"  time to all targets (T_S{', confirmed or gone' if r.ts_rule == 'confirmed_or_gone' else ''}): "
        f"{_ts_words(r)}",
        *_departure_lines(r),
        f"  false confirmations: {r.false_confirmations}",
    ]
    for c in r.confirmations:
        lines.append(
            f"    vehicle {c.vehicle} t={c.time:7.1f} s target T{c.target + 1} "
            f"({c.north:.0f}, {c.east:.0f}) {c.distance:.0f} m off"
        )
    if r.complete:
        reasons = sorted({e.how for e in r.ends if e.name != "emulator"})
        lines.append(f"  complete: every vehicle ended normally ({', '.join(reasons)})")
    else:
        bad = [e for e in r.ends if not e.ok]
        why = (
            f"stopped by {r.stopped_by}"
            if r.stopped_by
            else f"{len(bad)} process(es) did not end normally"
        )
        lines.append(f"  NOT COMPLETE ({why}); the figures above cover what was flown:")
        lines.extend(_table(r.ends))
    lines.extend(_check_lines(r))
    for e in r.ends:
        for stray in e.strays:
            lines.append(
                f"  stray: {e.name} heard another sender with its system id, {stray}; ignored"
            )
    lines.extend(flight_log_lines(out, r.vehicles))
    lines.append(f"  results: {out / 'results.json'}")
    return lines
