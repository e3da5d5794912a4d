"""Everything a fleet run needs, checked before any process starts: arguments, profile, run
directory and ports. Each refusal names the argument, the value and the limit."""

from __future__ import annotations

import json
import tempfile
from dataclasses import dataclass
from pathlib import Path

from companion.mission.study_only import study_only_refusal
from companion.telemetry.events import LogFormatError
from companion.telemetry.mission_log import read_log
from mdm_ground.errors import GroundError
from mdm_ground.fleet.options import FleetOptions
from mdm_ground.fleet.ports import PortBlock, check_base_port, free_port_block
from mdm_profiles import MissionProfile
from mdm_profiles.ceiling import CeilingError, check_ceiling

MAX_VEHICLES = 254
"""MAVLink system ids 1..254 (255 is a ground station); vehicle i is system i+1 in the
emulator (sim_vehicle_stub/config.py) and in every companion."""
RUN_FILE = "run.json"
"""What the run was asked to do; written before the processes start."""


class FleetInputError(GroundError, ValueError):
    """A fleet run refused before start; the message says what, where and the limit."""


@dataclass(frozen=True)
class FleetPlan:
    """A checked run: how many vehicles, which ports, which companions start."""

    vehicles: int
    ports: PortBlock | None
    """None: real vehicles (no emulator, no local port block)."""
    start: tuple[int, ...]
    """Vehicles whose companion starts (all of them unless resuming)."""
    earlier: dict[int, str]
    """Resuming: vehicles that ended in an earlier run, with how they ended."""


def check_arguments(o: FleetOptions, profile: MissionProfile) -> int:
    """The vehicle count (the profile's when not given) after checking every numeric argument."""
    limit = min(profile.fleet.vehicles, MAX_VEHICLES)
    n = profile.fleet.vehicles if o.vehicles is None else o.vehicles
    if not 1 <= n <= limit:
        why = (
            f"profile {profile.name!r} has {profile.fleet.vehicles} vehicles"
            if limit == profile.fleet.vehicles
            else f"MAVLink system ids stop at {MAX_VEHICLES}"
        )
        raise FleetInputError(f"--vehicles {n}: must be 1..{limit} ({why})")
    try:
        check_ceiling(profile, n)
    except CeilingError as exc:
        raise FleetInputError(f"--vehicles {n}: {exc}") from exc
    refusal = study_only_refusal(profile)
    if refusal is not None:
        raise FleetInputError(refusal)
    if not o.duration > 0:
        raise FleetInputError(f"--duration {o.duration:g}: must be > 0 (search time, sim s)")
    if not o.speedup >= 0:
        raise FleetInputError(f"--speedup {o.speedup:g}: must be >= 0 (0: flat out)")
    if not o.wall_limit > 0:
        raise FleetInputError(f"wall limit {o.wall_limit:g}: must be > 0 wall s")
    if not o.link_timeout > 0:
        raise FleetInputError(f"--link-timeout {o.link_timeout:g}: must be > 0 wall s")
    if not o.land_wait >= 0:
        raise FleetInputError(f"--land-wait {o.land_wait:g}: must be >= 0 sim s")
    return n


def _used(out: Path) -> list[str]:
    names = [RUN_FILE, "results.json", "emulator.log"]
    found = [name for name in names if (out / name).exists()]
    return found + sorted(p.name for p in out.glob("mission-*.jsonl"))


def check_out(out: Path, resume: bool) -> None:
    """``out`` is (or can be made) a writable directory, unused unless resuming."""
    if out.exists() and not out.is_dir():
        raise FleetInputError(f"--out {out}: exists and is not a directory")
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=out):
            pass
    except OSError as exc:
        raise FleetInputError(f"--out {out}: not writable ({exc.strerror})") from None
    used = _used(out)
    if used and not resume:
        raise FleetInputError(
            f"--out {out}: already holds a run ({', '.join(used[:3])}); choose a new "
            "directory, or add --resume to continue that run"
        )
    if resume and not used:
        raise FleetInputError(f"--resume: {out} holds no run to continue")


def _resume_plan(
    o: FleetOptions, profile: MissionProfile, n: int
) -> tuple[tuple[int, ...], dict[int, str]]:
    """Which companions start again, after checking the earlier run was the same mission."""
    if profile.target_motion is not None:
        raise FleetInputError(
            f"--resume: profile {profile.name!r} has moving targets, scored against the "
            "emulator's clock, which a restarted emulator starts again from 0"
        )
    try:
        earlier = json.loads((o.out / RUN_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise FleetInputError(f"--resume: {o.out / RUN_FILE} unreadable ({exc})") from None
    asked = {"profile": profile.name, "vehicles": n, "seed": o.seed, "duration": o.duration}
    for key, value in asked.items():
        if earlier.get(key) != value:
            raise FleetInputError(
                f"--resume: {o.out} was a run with {key} {earlier.get(key)!r}, not {value!r}"
            )
    ended: dict[int, str] = {}
    for i in range(n):
        try:
            end = read_log(o.out / f"mission-{i}.jsonl").end()
        except LogFormatError as exc:
            raise FleetInputError(f"--resume: {exc}") from None
        if end is not None:
            ended[i] = end.reason
    start = tuple(i for i in range(n) if i not in ended)
    if not start:
        raise FleetInputError(
            f"--resume: every vehicle of {o.out} already ended; nothing to continue"
        )
    return start, ended


def plan_fleet(o: FleetOptions, profile: MissionProfile, *, emulator: bool = True) -> FleetPlan:
    """Check everything in order (arguments, run directory, ports: only for the emulator's
    vehicles); FleetInputError if not."""
    n = check_arguments(o, profile)
    check_out(o.out, o.resume)
    start, earlier = _resume_plan(o, profile, n) if o.resume else (tuple(range(n)), {})
    ports = None
    if emulator:
        ports = check_base_port(o.base_port, n) if o.base_port is not None else free_port_block(n)
    return FleetPlan(vehicles=n, ports=ports, start=start, earlier=earlier)
