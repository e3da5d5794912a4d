"""A MAVLink conformance check that any vehicle endpoint (emulator, PX4 SITL, ArduPilot SITL) can
be run against: what MAVSDK, pymavlink and MAVProxy need from an autopilot, check by check."""

from mavlink_conformance.checks import CHECKS, CheckResult, run_checks

__all__ = ["CHECKS", "CheckResult", "run_checks"]
