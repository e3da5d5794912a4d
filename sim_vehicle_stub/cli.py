"""`sim-vehicle`: run N emulated MAVLink vehicles in one world from a mission profile."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import logging
import signal
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

from mavlink_wire import ENV_VAR, load_signing_key
from mdm_core.ports import GCS_UDP, TCP_BASE, VEHICLE_OWN_UDP_BASE, VEHICLE_UDP_BASE
from mdm_profiles import ProfileError, builtin_profile, builtin_profiles, load_profile
from mdm_profiles.schema import MissionProfile
from mdm_provenance import add_version_flag, extras
from sim_vehicle_stub.config import EmulatorConfig
from sim_vehicle_stub.personas import persona_names


def _profile(ref: str) -> MissionProfile:
    if ref in builtin_profiles():
        return builtin_profile(ref)
    return load_profile(ref)


def _speedup(text: str) -> float | None:
    if text in ("0", "max"):
        return None
    value = float(text)
    if value <= 0:
        raise argparse.ArgumentTypeError("speedup must be > 0, or 0/max for flat out")
    return value


def _personas(text: str) -> tuple[str, ...]:
    names = tuple(s.strip() for s in text.split(",") if s.strip())
    unknown = [n for n in names if n not in persona_names()]
    if not names or unknown:
        what = f"unknown persona {unknown[0]!r}" if unknown else "no persona given"
        raise argparse.ArgumentTypeError(f"{what}; known: {', '.join(persona_names())}")
    return names


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="sim-vehicle", description=__doc__)
    add_version_flag(p)
    p.add_argument("--profile", default="paper-fixed", help="built-in name or YAML path")
    p.add_argument("-n", "--vehicles", type=int, help="fleet size (default: the profile's)")
    p.add_argument(
        "--persona",
        type=_personas,
        default=("px4",),
        help=f"persona per vehicle, comma-separated and cycled ({', '.join(persona_names())})",
    )
    p.add_argument("--host", default="127.0.0.1", help="address the vehicles send first to")
    p.add_argument(
        "--base-port", type=int, default=VEHICLE_UDP_BASE, help="vehicle i sends to base+i"
    )
    p.add_argument("--bind-host", default="127.0.0.1")
    p.add_argument(
        "--bind-port-base",
        type=int,
        default=VEHICLE_OWN_UDP_BASE,
        help="vehicle i listens on base+i (0: any)",
    )
    p.add_argument("--tcp", action="store_true", help="TCP server per vehicle on tcp-base+10i")
    p.add_argument("--tcp-base", type=int, default=TCP_BASE)
    p.add_argument("--gcs", action="store_true", help="all vehicles also to UDP gcs-port")
    p.add_argument("--gcs-port", type=int, default=GCS_UDP)
    p.add_argument("--gcs-host", help="where --gcs sends (default: --host)")
    p.add_argument("--speedup", type=_speedup, default=1.0, help="sim/wall ratio; 0 or max")
    p.add_argument("--sim-step", type=float, default=0.05, help="physics step, sim s")
    p.add_argument("--telemetry-hz", type=float, default=10.0, help="streams, per sim s")
    p.add_argument(
        "--lockstep",
        action="store_true",
        help="hold sim time until the streaming clients' setpoints are current",
    )
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--events", type=Path, help="JSON-lines ground-truth and event log")
    p.add_argument("--stats", type=Path, help="write link counters as JSON on exit")
    p.add_argument("--duration", type=float, help="stop after this many sim seconds")
    p.add_argument("--battery-endurance", type=float, default=7200.0, help="sim s")
    p.add_argument(
        "--no-scale-timeouts",
        action="store_true",
        help="keep real failsafe time-outs at speed-ups (clients must stream at sim rate)",
    )
    p.add_argument("--flood-rate", type=float, default=5000.0, help="datagrams/s per endpoint")
    p.add_argument(
        "--signing-key-file",
        type=Path,
        help=f"MAVLink 2 signing: file holding the passphrase (default: ${ENV_VAR}; neither: off)",
    )
    p.add_argument("--log-level", default="INFO")
    return p


def config_from_args(args: argparse.Namespace) -> EmulatorConfig:
    return EmulatorConfig(
        profile=_profile(args.profile),
        vehicles=args.vehicles,
        personas=args.persona,
        host=args.host,
        base_port=args.base_port,
        bind_host=args.bind_host,
        bind_port_base=args.bind_port_base,
        tcp=args.tcp,
        tcp_base=args.tcp_base,
        gcs=args.gcs,
        gcs_port=args.gcs_port,
        gcs_host=args.gcs_host,
        speedup=args.speedup,
        sim_step=args.sim_step,
        telemetry_hz=args.telemetry_hz,
        lockstep=args.lockstep,
        seed=args.seed,
        events=args.events,
        battery_endurance=args.battery_endurance,
        scale_timeouts=not args.no_scale_timeouts,
        flood_rate=args.flood_rate,
        signing_key=load_signing_key(args.signing_key_file),
    )


@contextlib.contextmanager
def _stops_noted() -> Iterator[list[int]]:
    """SIGINT and SIGTERM noted, not acted on, until the event loop takes them over. A stop that
    arrives while the emulator starts (numba loading its kernels takes about a second) then
    ends it cleanly, exit status 0, instead of killing it. Only the main thread can set
    handlers; the previous ones are restored on the way out."""
    noted: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield noted
        return
    previous = {
        sig: signal.signal(sig, lambda signum, _frame: noted.append(signum))
        for sig in (signal.SIGINT, signal.SIGTERM)
    }
    try:
        yield noted
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


async def _serve(
    config: EmulatorConfig, duration: float | None, stats: Path | None, stops: list[int]
) -> None:
    # Imported here, after the stop handlers: with it come numba and the compiled kernels.
    from sim_vehicle_stub.emulator import Emulator

    emulator = Emulator(config)
    task = asyncio.create_task(emulator.run(duration))
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError):
            loop.add_signal_handler(sig, task.cancel)
    if stops:  # asked to stop before the loop's handlers were in place
        task.cancel()
    with contextlib.suppress(asyncio.CancelledError):
        await task
    if stats is not None:
        stats.write_text(json.dumps(emulator.stats(), indent=1))


def main(argv: list[str] | None = None) -> int:
    with _stops_noted() as stops:
        args = build_parser().parse_args(argv)
        extras.require("sim-vehicle", "emulator")  # before the emulator imports numba
        logging.basicConfig(
            level=args.log_level.upper(), format="%(asctime)s %(levelname)s %(name)s: %(message)s"
        )
        try:
            config = config_from_args(args)
        except (ProfileError, ValueError, OSError) as exc:
            print(f"sim-vehicle: {exc}", file=sys.stderr)
            return 2
        try:
            asyncio.run(_serve(config, args.duration, args.stats, stops))
        except OSError as exc:
            print(f"sim-vehicle: {exc}", file=sys.stderr)
            return 1
        return 0


if __name__ == "__main__":
    sys.exit(main())
