"""Imports run one way: mdm_profiles <- mdm_core <- {companion, sim_vehicle_stub, mdm_montecarlo},
and companion (the vehicle side) <- mdm_ground (the ground tools), never back: a vehicle installed
without the ground tools' dependencies still runs ``companion run``.
Inside mdm_montecarlo its rooms run one way too: kernels <- engines <- study <- commands.

Every import statement of every module (also those inside functions) is read with ``ast``; a
package may import only the packages listed for it here.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

ALLOWED: dict[str, set[str]] = {
    "mdm_profiles": set(),
    "mavlink_wire": set(),
    "mdm_provenance": set(),
    "mdm_core": {"mdm_profiles"},
    "companion": {"mdm_core", "mdm_profiles", "mavlink_wire", "mdm_provenance"},
    "mdm_ground": {"companion", "mdm_core", "mdm_profiles", "mavlink_wire", "mdm_provenance"},
    "sim_vehicle_stub": {"mdm_core", "mdm_profiles", "mavlink_wire", "mdm_provenance"},
    "mdm_montecarlo": {"mdm_core", "mdm_profiles", "mdm_provenance"},
    "mavlink_conformance": {"mavlink_wire", "mdm_provenance"},
}


def _imported_packages(path: Path) -> set[str]:
    """The top-level names of the project's packages that ``path`` imports."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.add(node.module.split(".")[0])
    return found & set(ALLOWED)


@pytest.mark.parametrize("package", sorted(ALLOWED))
def test_package_imports_only_the_layers_below_it(package: str) -> None:
    wrong = {
        f"{path.relative_to(REPO)} imports {other}"
        for path in sorted((REPO / package).rglob("*.py"))
        for other in _imported_packages(path) - ALLOWED[package] - {package}
    }
    assert not wrong, "\n".join(sorted(wrong))


def test_the_check_sees_an_import_inside_a_function(tmp_path: Path) -> None:
    module = tmp_path / "m.py"
    module.write_text("def f():\n    from sim_vehicle_stub.vehicle import Vehicle\n")
    assert _imported_packages(module) == {"sim_vehicle_stub"}


ROOMS = ("kernels", "engines", "study", "commands")
"""mdm_montecarlo's rooms, each importing only the rooms before it (mdm_montecarlo/__init__.py)."""


def _montecarlo_rooms(path: Path) -> set[str]:
    """The rooms of mdm_montecarlo that ``path`` imports."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        names = [a.name for a in node.names] if isinstance(node, ast.Import) else []
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
        found.update(n.split(".")[1] for n in names if n.startswith("mdm_montecarlo."))
    return found & set(ROOMS)


def test_montecarlo_rooms_import_only_the_rooms_before_them() -> None:
    wrong = {
        f"{path.relative_to(REPO)} imports mdm_montecarlo.{other}"
        for room in ROOMS
        for path in sorted((REPO / "mdm_montecarlo" / room).rglob("*.py"))
        for other in _montecarlo_rooms(path) - set(ROOMS[: ROOMS.index(room) + 1])
    }
    assert not wrong, "\n".join(sorted(wrong))


def test_the_room_check_sees_an_import_up(tmp_path: Path) -> None:
    module = tmp_path / "m.py"
    module.write_text("from mdm_montecarlo import study\nimport mdm_montecarlo.engines.runner\n")
    assert _montecarlo_rooms(module) == {"study", "engines"}
