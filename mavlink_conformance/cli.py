"""`mavlink-conformance ADDRESS`: check a MAVLink vehicle endpoint; exit 0 when all checks pass."""

from __future__ import annotations

import argparse
import json
import logging
import sys
from dataclasses import asdict

from mavlink_conformance.checks import run_checks
from mdm_provenance import add_version_flag


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="mavlink-conformance", description=__doc__)
    add_version_flag(p)
    p.add_argument("address", help="pymavlink address, e.g. udpin:0.0.0.0:14540 or tcp:HOST:5760")
    p.add_argument("--sysid", type=int, help="vehicle system id (default: first autopilot heard)")
    p.add_argument("--timeout", type=float, default=5.0, help="per-step wait, wall seconds")
    p.add_argument("--source-system", type=int, default=250)
    p.add_argument("--json", action="store_true", help="print results as JSON")
    p.add_argument(
        "--hostile",
        action="store_true",
        help="also send NaN parameters (a takeoff); may crash the autopilot checked",
    )
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    if args.hostile:
        print(
            "warning: --hostile sends NaN parameters; they may crash the autopilot "
            "(ArduCopter SITL aborts on a NaN takeoff)",
            file=sys.stderr,
        )
    results = run_checks(
        args.address,
        sysid=args.sysid,
        timeout=args.timeout,
        source_system=args.source_system,
        hostile=args.hostile,
    )
    if args.json:
        print(json.dumps([asdict(r) for r in results], indent=1))
    else:
        for r in results:
            print(r.line())
        print(f"{sum(r.passed for r in results)}/{len(results)} checks passed")
    return 0 if results and all(r.passed for r in results) else 1


if __name__ == "__main__":
    sys.exit(main())
