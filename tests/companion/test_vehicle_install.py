"""The vehicle side installed alone, as on a vehicle's own computer: the package's wheel, no
extra, in a fresh virtual environment (dependencies from the package index). It holds no module
of any extra, its ground, emulator and study commands refuse naming their install, and its
`companion run` flies a search against the emulator started from the project's environment."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from mdm_provenance import extras
from tests.vehicle_venv import build_wheel, fly, make_venv

pytestmark = pytest.mark.usefixtures("fleet_processes")

EXTRA_MODULES = sorted(set().union(*map(set, extras.MODULES.values())))


@pytest.fixture(scope="module")
def install_vehicle_venv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The vehicle side alone, in a virtual environment of its own."""
    work = tmp_path_factory.mktemp("vehicle-install")
    return make_venv(work / "venv", build_wheel(work / "wheel"))


def test_the_vehicle_install_holds_no_module_of_any_extra(install_vehicle_venv: Path) -> None:
    code = "import importlib.util as u, sys; print(' '.join(m for m in sys.argv[1:] if u.find_spec(m)))"
    found = subprocess.run(
        [str(install_vehicle_venv / "bin" / "python"), "-c", code, *EXTRA_MODULES],
        capture_output=True,
        text=True,
        check=True,
        timeout=60,
    ).stdout.split()
    assert found == []


@pytest.mark.parametrize(
    ("argv", "extra"),
    [
        (["sim-vehicle", "--vehicles", "1"], "emulator"),
        (["mdm-montecarlo", "run", "--profile", "paper-fixed"], "study"),
        (["companion", "fleet", "--profile", "paper-fixed"], "ground"),
        (["companion", "map", "runs/x"], "ground"),
    ],
)
def test_each_command_of_an_extra_names_its_install_in_one_line(
    install_vehicle_venv: Path, argv: list[str], extra: str, tmp_path: Path
) -> None:
    done = subprocess.run(
        [str(install_vehicle_venv / "bin" / argv[0]), *argv[1:]],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=60,
        check=False,
    )
    lines = (done.stdout + done.stderr).splitlines()
    assert done.returncode == 2, lines
    assert len(lines) == 1, lines
    assert lines[0].endswith(f"pip install 'mdm-search[{extra}]'"), lines
    assert not list(tmp_path.iterdir())


def test_companion_run_of_the_vehicle_install_flies_and_lands(
    install_vehicle_venv: Path, tmp_path: Path
) -> None:
    flight = fly(install_vehicle_venv, tmp_path / "run")
    log = (flight.out / "companion-0.log").read_text()
    assert flight.returncode == 0, log[-3000:]
    seen = flight.vehicle
    assert seen.armed_ever, "the vehicle never armed"
    assert seen.distance > 200.0, f"flew {seen.distance:.0f} m"
    assert not seen.armed, "still armed after the companion ended"
    assert seen.alt < 1.0, f"ended {seen.alt:.1f} m up"
    assert "no run map drawn: the ground tools are not installed" in log
    print(
        f"vehicle install flew {seen.distance:.0f} m, landed, disarmed; "
        f"companion run peak RSS {flight.max_rss_mb:.0f} MB"
    )
