"""The extras as pyproject.toml declares them and as the commands check them: the default install
is the vehicle side alone, and a command whose extra is missing says which `pip install` brings
it, in one line, exit 2."""

from __future__ import annotations

import importlib.util
import re
import tomllib
from importlib.machinery import ModuleSpec
from pathlib import Path

import pytest

from companion import cli as companion_cli
from mdm_montecarlo import entry as montecarlo_entry
from mdm_provenance import extras
from sim_vehicle_stub import cli as emulator_cli

PYPROJECT = tomllib.loads((Path(__file__).resolve().parents[2] / "pyproject.toml").read_text())
PROJECT = PYPROJECT["project"]
IMPORT_NAMES = {"pyyaml": "yaml"}
"""Distribution name -> module name, where the two differ."""


def _modules(requirements: list[str]) -> set[str]:
    """The top-level modules ``requirements`` bring (a ``dask[distributed]`` brings both)."""
    found: set[str] = set()
    for text in requirements:
        name, extra = re.match(r"([A-Za-z0-9_.-]+)(?:\[([^]]*)\])?", text).groups()  # type: ignore[union-attr]
        name = name.lower()
        if name == PROJECT["name"]:
            continue
        found.add(IMPORT_NAMES.get(name, name))
        if name == "dask" and extra:
            found.update(e.strip() for e in extra.split(","))
    return found


@pytest.mark.parametrize("extra", sorted(extras.MODULES))
def test_each_extras_modules_are_what_pyproject_installs_for_it(extra: str) -> None:
    assert _modules(PROJECT["optional-dependencies"][extra]) == set(extras.MODULES[extra])


def test_the_default_install_brings_no_module_of_any_extra() -> None:
    default = _modules(PROJECT["dependencies"])
    assert default == {"numpy", "pydantic", "yaml", "pymavlink", "mavsdk", "aiomqtt", "pymap3d"}
    every_extra = set().union(*map(set, extras.MODULES.values()))
    assert not default & every_extra


def test_all_is_every_extra_and_dev_brings_all() -> None:
    optional = PROJECT["optional-dependencies"]
    assert optional["all"] == [f"mdm-search[{','.join(sorted(extras.MODULES))}]"]
    assert "mdm-search[all]" in optional["dev"]


def _hide(monkeypatch: pytest.MonkeyPatch, module: str) -> None:
    """``module`` looks not installed to :mod:`mdm_provenance.extras`."""
    real = importlib.util.find_spec

    def find_spec(name: str) -> ModuleSpec | None:
        return None if name == module else real(name)

    monkeypatch.setattr(extras, "find_spec", find_spec)


def test_nothing_is_refused_where_every_extra_is_installed() -> None:
    assert all(extras.refusal("x", extra) is None for extra in extras.MODULES)


@pytest.mark.parametrize(
    ("argv", "run", "line"),
    [
        (
            ["--vehicles", "1"],
            emulator_cli.main,
            "sim-vehicle: needs the [emulator] extra (numba is not installed): "
            "pip install 'mdm-search[emulator]'",
        ),
        (
            ["run", "--profile", "paper-fixed"],
            montecarlo_entry.main,
            "mdm-montecarlo: needs the [study] extra (numba is not installed): "
            "pip install 'mdm-search[study]'",
        ),
        (
            ["fleet", "--profile", "paper-fixed"],
            companion_cli.main,
            "companion fleet: needs the [emulator] extra (numba is not installed): "
            "pip install 'mdm-search[emulator]'",
        ),
    ],
)
def test_a_command_without_its_extra_names_the_install_in_one_line_exit_2(
    argv: list[str],
    run: object,
    line: str,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    tmp_path: Path,
) -> None:
    monkeypatch.chdir(tmp_path)  # a fleet that did start would write its run here
    _hide(monkeypatch, "numba")
    with pytest.raises(SystemExit) as stop:
        run(argv)  # type: ignore[operator]
    assert stop.value.code == 2
    captured = capsys.readouterr()
    assert captured.err == line + "\n"
    assert not list(tmp_path.iterdir())


def test_the_ground_commands_name_the_ground_extra_when_one_of_its_modules_is_missing(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    _hide(monkeypatch, "amqtt")
    assert companion_cli.main(["watch", "--profile", "paper-fixed"]) == 2
    assert capsys.readouterr().out == (
        "companion watch: the ground tools are not installed (amqtt is missing): "
        "pip install 'mdm-search[ground]'\n"
    )


def test_a_fleet_of_real_vehicles_does_not_need_the_emulator(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    _hide(monkeypatch, "numba")
    missing = tmp_path / "vehicles.yaml"
    code = companion_cli.main(
        ["fleet", "--profile", "paper-fixed", "--vehicles-file", str(missing)]
    )
    assert code == 2
    assert "extra" not in capsys.readouterr().err  # refused for its missing file instead
