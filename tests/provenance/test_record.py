"""The provenance record and every command's --version."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mdm_provenance import collect, cpu_seconds, package_version

REPO = Path(__file__).resolve().parents[2]
COMMANDS = ("mdm-montecarlo", "companion", "sim-vehicle", "mavlink-conformance")


def _pyproject_version() -> str:
    for line in (REPO / "pyproject.toml").read_text().splitlines():
        if line.startswith("version = "):
            return line.split('"')[1]
    raise AssertionError("pyproject.toml has no version line")


def test_the_package_version_is_pyprojects_and_the_changelog_begins_with_it() -> None:
    version = _pyproject_version()
    assert package_version() == version
    headings = [
        line for line in (REPO / "CHANGELOG.md").read_text().splitlines() if line.startswith("## ")
    ]
    assert headings[0] == f"## {version}"


def _head() -> str:
    done = subprocess.run(
        ["git", "-C", str(REPO), "rev-parse", "HEAD"], capture_output=True, text=True, check=False
    )
    return done.stdout.strip()


@pytest.mark.parametrize("command", COMMANDS)
def test_every_command_answers_version_with_the_version_and_commit(command: str) -> None:
    exe = Path(sys.executable).parent / command
    before = _head()  # others commit to this checkout meanwhile: HEAD before or after
    done = subprocess.run(
        [str(exe), "--version"], capture_output=True, text=True, timeout=60, check=False
    )
    after = _head()
    assert done.returncode == 0, done.stderr
    assert any(
        done.stdout.startswith(f"{command} {_pyproject_version()} (git {head[:12]}")
        for head in (before, after)
    ), done.stdout


def test_the_record_names_this_checkout_interpreter_and_cpu_and_survives_json() -> None:
    started, cpu = time.perf_counter(), cpu_seconds()
    sum(i * i for i in range(200_000))  # some CPU time to measure
    before = _head()
    record = json.loads(json.dumps(collect(seed=7, started=started, cpu_started=cpu).as_dict()))
    assert record["git_commit"] in (before, _head())
    assert isinstance(record["git_dirty"], bool)
    assert record["python"] == ".".join(map(str, sys.version_info[:3]))
    import numba
    import numpy

    assert (record["numpy"], record["numba"]) == (numpy.__version__, numba.__version__)
    assert record["seed"] == 7
    assert record["command_line"] == sys.argv
    assert record["cpu_model"]
    if Path("/proc/cpuinfo").exists() and "sse2" in Path("/proc/cpuinfo").read_text():
        assert "sse2" in record["cpu_vector_flags"]
    assert record["wall_s"] > 0
    assert record["cpu_s"] > 0
