"""What a test does when a service it needs is not there (a broker, a Docker engine, a SITL
build, Chromium): it skips, naming what is missing; under ``CI=true`` it fails instead, since
CI (``.ci/run``) provides every one of them and a skip there would hide a broken setup."""

from __future__ import annotations

import os
from typing import NoReturn

import pytest


def in_ci() -> bool:
    """Whether this run is CI's (``CI=true``, as GitHub Actions and ``.ci/run`` set it)."""
    return os.environ.get("CI", "").strip().lower() in ("true", "1", "yes")


def missing(what: str) -> NoReturn:
    """Skip the test because ``what`` is missing, or fail it under ``CI=true``."""
    if in_ci():
        pytest.fail(f"CI=true and {what}", pytrace=False)
    pytest.skip(what)
