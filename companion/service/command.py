"""`companion service`: write the systemd unit that starts one vehicle's `companion run` at boot.

    companion service [--out FILE|-] [--user USER] [--log-dir DIR] RUN-OPTIONS

RUN-OPTIONS are `companion run`'s (``--profile``, ``--vehicle``, ``--connect``, ``--system-id``,
``--mqtt`` ...), checked as `run` checks them before the unit is written (exit 2 naming what is
wrong); the unit adds the run directory, its log file and the per-boot mission rule."""

from __future__ import annotations

import argparse
import getpass
import os
import sys
from collections.abc import Callable
from pathlib import Path

from companion.errors import InputError
from companion.link.address import parse_address
from companion.service.unit_file import STATE_ROOT, UnitSpec, render

UNIT_DIR = Path("/etc/systemd/system")
_SET_BY_THE_UNIT = ("--log-file", "--new-mission-per-boot", "--no-map")
STOP_MARGIN = 60.0
"""Wall seconds past ``--land-wait`` and ``--flight-log-wait`` that systemd waits for the
companion after SIGTERM."""


def _absolute(arg: str) -> str:
    """A relative path of a file that exists here (a profile, a key file) made absolute."""
    if arg.startswith("-") or os.path.isabs(arg) or not os.path.exists(arg):
        return arg
    return os.path.abspath(arg)


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="companion service",
        description=__doc__.split("\n\n")[0] if __doc__ else None,
        add_help=False,
    )
    add_service_options(p)
    return p


def add_service_options(p: argparse.ArgumentParser) -> None:
    """The options of `companion service` itself (the rest are `companion run`'s)."""
    p.add_argument(
        "--out",
        help=f"unit file to write, '-' for stdout (default {UNIT_DIR}/mdm-companion-I.service)",
    )
    p.add_argument("--user", help="account it runs as (default: the one invoking sudo, else you)")
    p.add_argument(
        "--log-dir",
        type=Path,
        help=f"run directory, kept across restarts (default {STATE_ROOT}/vehicle-I)",
    )


def add_service_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """`companion service` in `companion --help` (main() hands its arguments on itself)."""
    p = sub.add_parser(
        "service",
        help="write a systemd unit that starts `companion run` at boot",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_service_options(p)
    p.add_argument("run_options", nargs="*", metavar="RUN-OPTIONS")


def service_command(argv: list[str], check_run: Callable[[list[str]], argparse.Namespace]) -> int:
    """Write the unit; ``check_run`` parses and checks `companion run`'s options (raises
    ValueError, or exits 2 through argparse, naming what is wrong)."""
    if any(a in ("-h", "--help") for a in argv):
        build = argparse.ArgumentParser(prog="companion", add_help=False)
        add_service_parser(build.add_subparsers())
        build.parse_args(["service", "--help"])
    options, run_argv = _parser().parse_known_args(argv)
    for flag in _SET_BY_THE_UNIT:
        if flag in run_argv:
            raise InputError(f"{flag}: set by the unit itself; leave it out")
    run = check_run(run_argv)
    run_argv = [_absolute(a) for a in run_argv]  # the unit runs in the run directory
    log_dir = options.log_dir or STATE_ROOT / f"vehicle-{run.vehicle}"
    link = run.connect or f"udpin:0.0.0.0:{run.base_port + run.vehicle}"
    address = parse_address(link)
    spec = UnitSpec(
        companion=Path(sys.executable).parent / "companion",
        run_argv=tuple(run_argv),
        log_dir=log_dir.absolute(),
        description=f"MDM search companion: vehicle {run.vehicle} of {run.profile} over {link}",
        user=options.user or os.environ.get("SUDO_USER") or getpass.getuser(),
        stop_timeout=run.land_wait + run.flight_log_wait + STOP_MARGIN,
        serial_device=Path(address.host) if address.is_serial else None,
    )
    text = render(spec)
    if options.out == "-":
        sys.stdout.write(text)
        return 0
    out = Path(options.out) if options.out else UNIT_DIR / f"mdm-companion-{run.vehicle}.service"
    try:
        out.write_text(text)
    except OSError as exc:
        raise InputError(
            f"cannot write the unit {out}: {exc.strerror or exc} (run it with sudo, or --out FILE)"
        ) from exc
    name = out.stem
    print(f"wrote {out}")
    print("  sudo systemctl daemon-reload")
    print(f"  sudo systemctl enable --now {name}   # start now and at every boot")
    print(f"  journalctl -u {name} -f               # its log; run directory {spec.log_dir}")
    return 0
