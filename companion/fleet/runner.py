"""`companion fleet`: start the emulator and one companion process per vehicle, watch, score."""

from __future__ import annotations

import argparse
import json
import logging
import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from companion.fleet.progress import progress_line, read_progress
from companion.fleet.scoring import EMULATOR_EVENTS, FleetResult, score
from companion.link.factory import check_signing_support
from companion.run_map.cli_args import map_after_run
from companion.telemetry.mqtt.cli_args import mqtt_argv, mqtt_spec
from mavlink_signing import load_signing_key
from mdm_core.search.pso import VARIANTS
from mdm_profiles import MissionProfile, load_profile

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class FleetOptions:
    """One fleet run on this machine."""

    profile: str
    out: Path
    vehicles: int | None = None
    speedup: float = 100.0
    duration: float = 300.0
    backend: str = "pymavlink"
    persona: str = "px4"
    setpoints: str = "velocity"
    seed: int = 1
    base_port: int = 14540
    quiet: bool = True
    wall_limit: float = 900.0
    """Wall seconds after which the run is stopped (companions get SIGTERM)."""
    mqtt_args: tuple[str, ...] = ()
    """--mqtt* flags passed to every companion (none: no MQTT unless the profile has it)."""
    signing_key_file: Path | None = None
    """MAVLink signing passphrase file for the emulator and the companions (they also inherit
    $MDM_MAVLINK_KEY)."""
    sensor_source: str | None = None
    """--sensor-source of every companion (None: the profile's sensor_source.kind)."""
    lockstep: bool = False
    """The emulator holds sim time until every companion answered the last position
    (sim-vehicle --lockstep): a loaded host slows the run instead of the companions skipping
    stale positions, so setpoints stay at the telemetry rate (10 Hz) in vehicle time. Costs
    speed (docs/companion.md). Always on flat out (speedup 0)."""


def emulator_command(o: FleetOptions, vehicles: int) -> list[str]:
    """The sim-vehicle command line for this run."""
    return [
        sys.executable, "-m", "sim_vehicle_stub.cli",
        "--profile", o.profile,
        "--vehicles", str(vehicles),
        "--speedup", str(o.speedup) if o.speedup > 0 else "max",
        "--persona", o.persona,
        "--base-port", str(o.base_port),
        "--bind-port-base", str(o.base_port + 200),
        "--seed", str(o.seed),
        "--events", str(o.out / EMULATOR_EVENTS),
        # flat out, the emulator would outrun the companions at unscaled failsafe time-outs
        *(["--lockstep"] if o.lockstep or o.speedup <= 0 else []),
        *_signing_args(o),
    ]  # fmt: skip


def companion_command(o: FleetOptions, vehicle: int) -> list[str]:
    """The `companion run` command line of one vehicle."""
    return [
        sys.executable, "-m", "companion.cli", "run",
        "--profile", o.profile,
        "--vehicle", str(vehicle),
        "--base-port", str(o.base_port),
        "--backend", o.backend,
        "--setpoints", o.setpoints,
        "--seed", str(o.seed),
        "--log-dir", str(o.out),
        "--duration", str(o.duration),
        "--land-wait", "0",
        *(["--sensor-source", o.sensor_source] if o.sensor_source else []),
        "--dedicated-link",
        *o.mqtt_args,
        *_signing_args(o),
    ]  # fmt: skip


def _signing_args(o: FleetOptions) -> list[str]:
    return ["--signing-key-file", str(o.signing_key_file)] if o.signing_key_file else []


def run_fleet(o: FleetOptions) -> FleetResult:
    """Fly one fleet mission; returns its scored result (also written to out/results.json)."""
    profile = load_profile(o.profile)
    n = o.vehicles or profile.fleet.vehicles
    # a bad key or a backend that cannot sign fails here, not in every process
    check_signing_support(o.backend, load_signing_key(o.signing_key_file))
    o.out.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    started = time.perf_counter()
    with (o.out / "emulator.log").open("w") as emu_log:
        emulator = subprocess.Popen(
            emulator_command(o, n), stdout=emu_log, stderr=subprocess.STDOUT, env=env
        )
        companions: list[subprocess.Popen[bytes]] = []
        try:
            for i in range(n):
                with (o.out / f"companion-{i}.log").open("w") as f:
                    companions.append(
                        subprocess.Popen(companion_command(o, i), stdout=f, stderr=subprocess.STDOUT, env=env)
                    )  # fmt: skip
            _watch(o, profile, n, companions, started, emulator)
        finally:
            for p in companions:
                _stop(p)
            _stop(emulator)
    result = score(profile, o.out, n, o.duration, virtual_seed=_virtual_seed(o, profile))
    (o.out / "results.json").write_text(json.dumps(result.as_json(), indent=2, default=str))
    map_after_run(o.out, profile, list(range(n)), "map")
    log.info("fleet done in %.1f s wall", time.perf_counter() - started)
    return result


def _watch(
    o: FleetOptions,
    profile: MissionProfile,
    n: int,
    companions: list[subprocess.Popen[bytes]],
    started: float,
    emulator: subprocess.Popen[bytes],
) -> None:
    real = sum(not t.false_target for t in profile.targets)
    last_print, last_line = 0.0, ""
    while any(p.poll() is None for p in companions):
        time.sleep(0.5)
        now = time.perf_counter()
        if emulator.poll() is not None:
            log.error("the emulator exited (code %s); see %s", emulator.returncode,
                      o.out / "emulator.log")  # fmt: skip
            break
        if now - started > o.wall_limit:
            log.warning("wall limit %.0f s reached; stopping the companions", o.wall_limit)
            break
        if not o.quiet and now - last_print >= 2.0:
            views = read_progress(o.out, n)
            found = score(profile, o.out, n, o.duration, virtual_seed=_virtual_seed(o, profile)).tnc
            line = progress_line(views, found, real)
            if line != last_line or now - last_print >= 10.0:
                print(line, flush=True)
                last_print, last_line = now, line


def _virtual_seed(o: FleetOptions, profile: MissionProfile) -> int | None:
    """The companions' seed when they read virtual sensors (scored against that world)."""
    virtual = (o.sensor_source or profile.sensor_source.kind) == "virtual"
    return o.seed if virtual else None


def _stop(p: subprocess.Popen[bytes]) -> None:
    if p.poll() is None:
        p.send_signal(signal.SIGTERM)
        try:
            p.wait(timeout=10)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()


def fleet_command(args: argparse.Namespace) -> int:
    """`companion fleet`: run, then print a summary (or JSON)."""
    out = args.out or Path("runs") / time.strftime("fleet-%Y%m%d-%H%M%S")
    profile = load_profile(args.profile)
    # Bad --mqtt* flags, or a swarm kind without a broker, fail here, not N times.
    if mqtt_spec(args, profile.mqtt) is None and profile.policy.kind in VARIANTS:
        raise ValueError(
            f"profile {profile.name!r}: policy.kind {profile.policy.kind!r} shares the swarm's "
            "bests over MQTT; configure a broker (--mqtt HOST[:PORT] or the profile's mqtt:)"
        )
    opts = FleetOptions(
        profile=args.profile, out=out, vehicles=args.vehicles, speedup=args.speedup,
        duration=args.duration, backend=args.backend, persona=args.persona,
        setpoints=args.setpoints, seed=args.seed, base_port=args.base_port,
        quiet=args.quiet or args.json, mqtt_args=tuple(mqtt_argv(args)),
        signing_key_file=args.signing_key_file, lockstep=args.lockstep,
        sensor_source=args.sensor_source,
    )  # fmt: skip
    started = time.perf_counter()
    result = run_fleet(opts)
    wall = time.perf_counter() - started
    if args.json:
        print(json.dumps(result.as_json() | {"wall_s": round(wall, 1)}, default=str))
        return 0
    real = sum(1 for t in result.first_confirmation if t != float("inf"))
    print(f"\n{result.profile}: {result.vehicles} vehicles, {result.duration:.0f} sim s "
          f"in {wall:.1f} s wall")  # fmt: skip
    print(f"  targets confirmed (T_nc): {result.tnc}; distinct ever: {real}")
    ts = f"{result.ts:.1f} s" if not result.ts_capped else f"not all (capped {result.ts:.0f} s)"
    print(f"  time to all targets (T_S): {ts}")
    print(f"  false confirmations: {result.false_confirmations}")
    for c in result.confirmations:
        print(f"    vehicle {c.vehicle} t={c.time:7.1f} s target T{c.target + 1} "
              f"({c.north:.0f}, {c.east:.0f}) {c.distance:.0f} m off")  # fmt: skip
    print(f"  results: {out / 'results.json'}")
    return 0
