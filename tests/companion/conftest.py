"""Fixtures of the companion tests (helpers live in tests_companion_support.py)."""

from tests_companion_support import procs, small_profile

__all__ = ["procs", "small_profile"]
