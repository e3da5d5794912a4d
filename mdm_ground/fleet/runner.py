"""`companion fleet`: start the emulator and one companion process per vehicle, watch, score."""

from __future__ import annotations

import contextlib
import json
import logging
import os
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field, replace

from companion.link.factory import check_signing_support
from companion.mission.phase import Phase
from mavlink_wire import load_signing_key
from mdm_ground.fleet import processes
from mdm_ground.fleet.flight_checks import flight_checks
from mdm_ground.fleet.gcs import emulator_gcs_args
from mdm_ground.fleet.options import FleetOptions
from mdm_ground.fleet.outcome import emulator_end, exit_words, vehicle_end
from mdm_ground.fleet.preflight import RUN_FILE, FleetPlan, plan_fleet
from mdm_ground.fleet.processes import StopRequests
from mdm_ground.fleet.progress import (
    LEGEND,
    VehicleView,
    airborne,
    operator_ended,
    progress_line,
    read_progress,
)
from mdm_ground.fleet.scoring import EMULATOR_EVENTS, FleetResult, score
from mdm_ground.fleet.team import Team, is_real, open_team, team_size
from mdm_ground.fleet.vehicles_file import VehicleEntry
from mdm_ground.fleet.web_page import WebPage, start_page
from mdm_ground.run_map.cli_args import map_after_run
from mdm_profiles import MissionProfile, load_profile
from mdm_provenance import collect

__all__ = ["FleetOptions", "companion_command", "emulator_command", "run_fleet"]

log = logging.getLogger(__name__)
RESULTS = "results.json"
_POLL_S = 0.2
_EXIT_GRACE_S = 30.0
"""Wall seconds a companion gets to exit after a stop signal, or after its mission log says
done (with --land-wait 0 it exits within a few seconds: MQTT delivery is bounded by 7 s)."""
_HARD_STOP_S = 3.0
"""Wall seconds companions get to exit after a second stop signal before SIGKILL."""


def emulator_command(o: FleetOptions, vehicles: int, base_port: int) -> list[str]:
    """The sim-vehicle command line for this run."""
    return [
        sys.executable, "-m", "sim_vehicle_stub.cli",
        "--profile", o.profile,
        "--vehicles", str(vehicles),
        "--speedup", str(o.speedup) if o.speedup > 0 else "max",
        "--persona", o.persona,
        "--base-port", str(base_port),
        "--bind-port-base", str(base_port + vehicles),
        "--seed", str(o.seed),
        "--events", str(o.out / EMULATOR_EVENTS),
        # flat out, the emulator would outrun the companions at unscaled failsafe time-outs
        *(["--lockstep"] if o.lockstep or o.speedup <= 0 else []),
        *emulator_gcs_args(o.gcs),
        *_signing_args(o),
    ]  # fmt: skip


def companion_command(
    o: FleetOptions, vehicle: int, base_port: int, real: VehicleEntry | None = None
) -> list[str]:
    """The `companion run` command line of one vehicle (``real``: a vehicle of a fleet file or
    of --sitl, on its own link and system id, instead of the emulator's)."""
    if real is None:
        # the fleet, not each companion, waits for the landing (it reads the emulator's log)
        link = ["--base-port", str(base_port), "--land-wait", "0"]
    else:  # nothing but the vehicle knows when it landed: each companion waits for its own
        link = ["--connect", real.link, "--system-id", str(real.system_id),
                "--land-wait", str(o.land_wait), "--flight-log-wait", str(o.flight_log_wait)]  # fmt: skip
    source = real.sensor_source if real is not None and real.sensor_source else o.sensor_source
    # a fleet file's link may be shared with a ground station; the emulator's and SITL's are not
    dedicated = (real is None or o.sitl is not None) and o.gcs is None
    return [
        sys.executable, "-m", "companion.cli", "run",
        "--profile", o.profile,
        "--vehicle", str(vehicle),
        *link,
        "--backend", (real.backend if real is not None else None) or o.backend,
        "--setpoints", o.setpoints,
        "--seed", str(o.seed),
        "--log-dir", str(o.out),
        "--duration", str(o.duration),
        # one map of every vehicle at the end, drawn by the fleet: twelve companions each
        # importing matplotlib for their own were 8-10 of a 300 s run's 25-28 CPU-s
        "--no-map",
        # the emulator's clock runs at most this fast: a position whose clock leaps is dropped
        *(["--max-speedup", str(o.speedup)] if real is None and o.speedup > 0 else []),
        *(["--sensor-source", source] if source else []),
        *(["--dedicated-link"] if dedicated else []),
        *o.mqtt_args,
        *_signing_args(o),
    ]  # fmt: skip


def _signing_args(o: FleetOptions) -> list[str]:
    return ["--signing-key-file", str(o.signing_key_file)] if o.signing_key_file else []


def _say(text: str) -> None:
    """What the fleet does, on stderr (stdout may carry --json)."""
    print(text, file=sys.stderr, flush=True)


@dataclass
class _Stopped:
    """Why the watch ended early."""

    by: str | None = None
    emulator_early: bool = False
    at_once: bool = False
    signalled: bool = False
    """The companions got the fleet's first stop signal."""
    lost: dict[int, str] = field(default_factory=dict)
    """Real vehicles lost in flight (autopilot process gone, link silent), with the cause."""


def run_fleet(o: FleetOptions) -> FleetResult:
    """Fly one fleet mission; returns its scored result (also written to out/results.json).

    Everything is checked before a process starts (FleetInputError, PortError). A SIGINT or
    SIGTERM to the fleet (main thread only) ends every vehicle's mission with its end action and
    waits for the landing; a second one stops at once. results.json is written either way.
    """
    profile = load_profile(o.profile)
    # a bad key or a backend that cannot sign fails here, not in every process
    check_signing_support(o.backend, load_signing_key(o.signing_key_file))
    size = team_size(o, profile)
    plan = plan_fleet(
        o if size is None else replace(o, vehicles=size), profile, emulator=not is_real(o)
    )
    if plan.ports is None:
        team = open_team(o, profile, plan.vehicles)
        try:
            return _run_team(o, profile, plan, team)
        finally:
            team.stop()
    _say(f"fleet: {plan.ports.describe()}; logs in {o.out}")
    return _fly(o, profile, plan, None)


def _run_team(o: FleetOptions, profile: MissionProfile, plan: FleetPlan, team: Team) -> FleetResult:
    for i, e in sorted(team.entries.items()):
        _say(f"fleet: {e.name()}: {team.autopilots[i]}, disarmed on the ground")
    _say(f"fleet: {plan.vehicles} real vehicles, no emulator; logs in {o.out}")
    return _fly(o, profile, plan, team)


def _fly(
    o: FleetOptions, profile: MissionProfile, plan: FleetPlan, team: Team | None
) -> FleetResult:
    started = time.perf_counter()  # results.json's provenance: the flight's wall time
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    page = start_page(o, plan.vehicles, emulated=plan.ports is not None, env=env)
    if page is not None and page.broker is not None:
        o = replace(o, mqtt_args=page.broker.companion_args())
    _write_run_file(o, profile, plan, team, page)
    emulator = None
    if plan.ports is not None:
        # present from the start, so a run whose emulator never wrote is scored (nothing in range)
        (o.out / EMULATOR_EVENTS).touch()
        emulator = processes.start(
            emulator_command(o, plan.vehicles, plan.ports.base),
            o.out / "emulator.log",
            env,
            append=o.resume,
        )
    companions: dict[int, subprocess.Popen[bytes]] = {}
    stopped = _Stopped()
    requests = StopRequests()
    with requests.installed():
        try:
            for i in plan.start:
                companions[i] = processes.start(
                    companion_command(
                        o,
                        i,
                        plan.ports.base if plan.ports else 0,
                        team.entries[i] if team else None,
                    ),
                    o.out / f"companion-{i}.log",
                    env,
                    append=o.resume,
                )
            stopped = _watch(o, profile, plan, companions, emulator, requests, team)
        finally:
            if stopped.at_once or any(p.poll() is None for p in companions.values()):
                _stop_at_once(companions, signalled=stopped.signalled)
            if emulator is not None:
                processes.stop(emulator, 10.0)
            if page is not None:
                processes.stop(page.process, 5.0)
                if page.broker is not None:  # its passwords served this run alone
                    shutil.rmtree(page.broker.accounts, ignore_errors=True)
    return _finish(o, profile, plan, companions, emulator, stopped, started)


def _write_run_file(
    o: FleetOptions,
    profile: MissionProfile,
    plan: FleetPlan,
    team: Team | None,
    page: WebPage | None,
) -> None:
    run = {
        "profile": profile.name,
        "profile_arg": o.profile,
        "vehicles": plan.vehicles,
        "seed": o.seed,
        "duration": o.duration,
        "speedup": o.speedup,
        "backend": o.backend,
        "persona": o.persona,
        "base_port": plan.ports.base if plan.ports else None,
        "started": time.time(),
        "resumed_vehicles": list(plan.start) if o.resume else None,
        "mqtt": _broker_record(o, profile, page),
    }
    if team is not None:
        run |= {
            "vehicles_file": str(o.vehicles_file) if o.vehicles_file else None,
            "sitl": o.sitl,
            "sitl_speedup": o.sitl_speedup if o.sitl else None,
            "team": [
                e.model_dump() | {"heard_autopilot": team.autopilots[i]}
                for i, e in sorted(team.entries.items())
            ],
        }
    if o.resume:  # keep the first run's description; note the restart beside it
        earlier = json.loads((o.out / RUN_FILE).read_text(encoding="utf-8"))
        run = earlier | {"resumes": [*earlier.get("resumes", []), run]}
    (o.out / RUN_FILE).write_text(json.dumps(run, indent=2))


def _broker_record(
    o: FleetOptions, profile: MissionProfile, page: WebPage | None
) -> dict[str, str] | None:
    """Which broker the run used (None: no MQTT): the page's embedded one, or the one given."""
    if page is not None and page.broker is not None:
        b = page.broker
        return {"broker": "embedded", "server": b.server, "address": f"{b.host}:{b.port}"}
    if "--mqtt" in o.mqtt_args:
        address = o.mqtt_args[o.mqtt_args.index("--mqtt") + 1]
    elif profile.mqtt is not None:
        address = f"{profile.mqtt.host}:{profile.mqtt.port}"
    else:
        return None
    return {"broker": "external", "address": address}


def _watch(
    o: FleetOptions,
    profile: MissionProfile,
    plan: FleetPlan,
    companions: dict[int, subprocess.Popen[bytes]],
    emulator: subprocess.Popen[bytes] | None,
    requests: StopRequests,
    team: Team | None,
) -> _Stopped:
    """Until every companion has ended (and, after a stop or an operator's land or abort,
    every vehicle has landed: real vehicles' companions wait for their own landing)."""
    started = time.monotonic()
    stopped = _Stopped()
    grace = _EXIT_GRACE_S
    if team is not None:  # the companions wait for the landing: vehicle s at the SITL's speed
        grace += o.land_wait / (o.sitl_speedup if o.sitl else 1.0)
    silent_since: dict[int, float] = {}
    stop_at = land_by = None
    # Once every companion has ended: whether an operator's land or abort ended a mission.
    operator_landing: bool | None = None
    done_at: dict[int, float] = {}
    real = sum(not t.false_target for t in profile.targets)
    last_look, last_print, last_line = 0.0, 0.0, ""
    if not o.quiet:
        print(LEGEND, flush=True)
    while True:
        time.sleep(_POLL_S)
        now = time.monotonic()
        if requests.count >= 2:
            _say(f"fleet: second {requests.signal_name}: stopping every process at once")
            stopped.by = stopped.by or requests.signal_name
            stopped.at_once = True
            return stopped
        if team is not None:
            _lose_vehicles(o, team, companions, stopped, silent_since, now)
        if emulator is not None and emulator.poll() is not None:
            log.error(
                "the emulator exited (code %s); see %s", emulator.returncode, o.out / "emulator.log"
            )
            stopped.by = stopped.by or "the emulator's exit"
            stopped.emulator_early = True
            return stopped
        if stop_at is None and (requests.count or now - started > o.wall_limit):
            stopped.by = requests.signal_name if requests.count else "wall limit"
            stop_at = now
            _say(
                f"fleet: {stopped.by}: every vehicle flies its end action; waiting for the "
                "companions and the landing (Ctrl-C again to stop at once)"
            )
            for p in companions.values():
                processes.signal_one(p, signal.SIGINT)
            stopped.signalled = True
        alive = {i: p for i, p in companions.items() if p.poll() is None}
        if alive:
            if stop_at is not None and now - stop_at > grace:
                _say(
                    f"fleet: companions of vehicles {sorted(alive)} still running "
                    f"{grace:.0f} s after the stop; stopping them at once"
                )
                stopped.at_once = True
                return stopped
            if now - last_look >= 2.0:
                last_look = now
                views = read_progress(o.out, plan.vehicles)
                _end_hung(o, views, alive, done_at, now)
                # real vehicles whose link is silent while every other companion has ended
                lost = all(views[i].phase == Phase.LINK_LOST.value for i in alive)
                for i in alive:
                    if lost:
                        silent_since.setdefault(i, now)
                    else:
                        silent_since.pop(i, None)
                if not o.quiet:
                    line = _progress(o, profile, plan, companions, views, real)
                    if line != last_line or now - last_print >= 10.0:
                        print(line, flush=True)
                        last_print, last_line = now, line
            continue
        if emulator is None:  # each real vehicle's companion waited for its own landing
            return stopped
        if stop_at is None and operator_landing is None:
            # Read once: no mission log changes after its companion has ended.
            operator_landing = bool(operator_ended(o.out, plan.vehicles))
        if stop_at is None and not operator_landing:
            # Ended on their own (mission time): the search is over, the emulator may stop.
            return stopped
        # After a stop, or an operator's land or abort: the landing asked for is flown out.
        flying = airborne(o.out)
        if not flying:
            _say("fleet: every vehicle has landed")
            return stopped
        if land_by is None:
            wall = o.land_wait / o.speedup if o.speedup > 0 else o.land_wait / 50.0
            land_by = now + wall
            _say(
                f"fleet: waiting up to {wall:.0f} s wall ({o.land_wait:.0f} sim s) for "
                f"{len(flying)} vehicle(s) to land: {flying}"
            )
        elif now > land_by:
            _say(f"fleet: still in the air after {o.land_wait:.0f} sim s: {flying}")
            return stopped


def _lose_vehicles(
    o: FleetOptions,
    team: Team,
    companions: dict[int, subprocess.Popen[bytes]],
    stopped: _Stopped,
    silent_since: dict[int, float],
    now: float,
) -> None:
    """Real vehicles gone in flight: a SITL instance of this run that exited, or a link silent
    ``o.link_timeout`` wall s while every other companion had ended. Its companion is stopped at
    once (no end action can reach a vehicle without a link); the others fly on."""
    causes: dict[int, str] = {}
    for member in team.sitl:
        code = member.process.poll()
        if code is not None:
            causes[member.entry.index] = (
                f"its {member.entry.autopilot} SITL process exited"
                f"{exit_words(code)} (log {member.log})"
            )
    for i, since in silent_since.items():
        if now - since > o.link_timeout:
            causes.setdefault(
                i,
                f"link lost: no HEARTBEAT on {team.entries[i].link} for "
                f"{o.link_timeout:g} s after every other vehicle ended",
            )
    for i, cause in causes.items():
        if i in stopped.lost:
            continue
        stopped.lost[i] = cause
        _say(f"fleet: vehicle {i} lost: {cause}; stopping its companion, the others fly on")
        p = companions.get(i)
        if p is not None and p.poll() is None:
            _stop_at_once({i: p}, signalled=False)


def _end_hung(
    o: FleetOptions,
    views: list[VehicleView],
    alive: dict[int, subprocess.Popen[bytes]],
    done_at: dict[int, float],
    now: float,
) -> None:
    """SIGKILL a companion still running _EXIT_GRACE_S after its mission log said done (real
    vehicles: and the download of the autopilot's log): a process that never exits would hold
    the whole fleet (its outcome shows the kill)."""
    real = o.sitl is not None or o.vehicles_file is not None
    grace = _EXIT_GRACE_S + (o.flight_log_wait if real else 0.0)
    for i, p in alive.items():
        if views[i].phase != Phase.DONE.value:
            continue
        since = done_at.setdefault(i, now)
        if now - since > grace:
            _say(
                f"fleet: vehicle {i}'s companion still running {grace:.0f} s after its "
                f"mission ended; killing it (its tasks: {o.out / f'companion-{i}.log'})"
            )
            processes.signal_one(p, signal.SIGUSR1)  # `companion run` logs its asyncio tasks
            processes.wait_all([p], 1.0)
            processes.kill_group(p)


def _progress(
    o: FleetOptions,
    profile: MissionProfile,
    plan: FleetPlan,
    companions: dict[int, subprocess.Popen[bytes]],
    views: list[VehicleView],
    real: int,
) -> str:
    for i, p in companions.items():
        views[i].failed = p.poll() not in (None, 0)
    scored = score(
        profile, o.out, plan.vehicles, o.duration, virtual_seed=_virtual_seed(o, profile)
    )
    gone = scored.ts_gone if scored.ts_rule == "confirmed_or_gone" else None
    return progress_line(views, scored.tnc, real, gone)


def _virtual_seed(o: FleetOptions, profile: MissionProfile) -> int | None:
    """The companions' seed when they read virtual sensors (scored against that world)."""
    virtual = (o.sensor_source or profile.sensor_source.kind) == "virtual"
    return o.seed if virtual else None


def _stop_at_once(companions: dict[int, subprocess.Popen[bytes]], *, signalled: bool) -> None:
    """Each companion's second signal (it stops commanding and exits; ``signalled``: the first
    was sent already), then SIGKILL after _HARD_STOP_S."""
    live = [p for p in companions.values() if p.poll() is None]
    for _ in range(1 if signalled else 2):
        for p in live:
            processes.signal_one(p, signal.SIGINT)
        time.sleep(_POLL_S)  # two signals at once may arrive as one
    processes.wait_all(live, _HARD_STOP_S)
    for p in live:
        processes.kill_group(p)


def _finish(
    o: FleetOptions,
    profile: MissionProfile,
    plan: FleetPlan,
    companions: dict[int, subprocess.Popen[bytes]],
    emulator: subprocess.Popen[bytes] | None,
    stopped: _Stopped,
    started: float,
) -> FleetResult:
    result = score(
        profile, o.out, plan.vehicles, o.duration, virtual_seed=_virtual_seed(o, profile)
    )
    result.ends = [
        vehicle_end(
            o.out, i, companions[i].returncode if i in companions else None, plan.earlier.get(i)
        )
        for i in range(plan.vehicles)
    ]
    for i, cause in stopped.lost.items():
        result.ends[i] = replace(
            result.ends[i], how=f"lost: {cause}; {result.ends[i].how}", ok=False
        )
    if emulator is not None:
        result.ends.append(emulator_end(o.out, emulator.returncode, stopped.emulator_early))
    result.flight_checks = flight_checks(profile, o.out, plan.vehicles)
    result.stopped_by = stopped.by
    result.complete = stopped.by is None and all(e.ok for e in result.ends)
    path = o.out / RESULTS
    record = collect(seed=o.seed, started=started).as_dict()
    path.write_text(json.dumps(result.as_json() | {"provenance": record}, indent=2, default=str))
    with contextlib.redirect_stdout(sys.stderr):  # stdout may carry --json
        map_after_run(o.out, profile, list(range(plan.vehicles)), "map")
    return result
