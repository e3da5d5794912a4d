"""Imports run one way: mdm_profiles <- mdm_core <- {companion, sim_vehicle_stub, mdm_montecarlo},
and companion (the vehicle side) <- mdm_ground (the ground tools), never back: a vehicle installed
without the ground tools' dependencies still runs ``companion run``.

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
