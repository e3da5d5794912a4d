"""The table of the search policy's compiled twins in docs/architecture.md is true: each
reference it names exists in mdm_core/search, each twin in mdm_montecarlo/kernels, and each test named
for a pair imports the reference and the twin (or the compiled policy that calls it, named
beside it)."""

from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
_ROW = re.compile(r"^\| (`[^|]+`[^|]*) \| (`[^|]+`) \| (`[^|]+`) \|$", re.MULTILINE)
_NAME = re.compile(r"`([^`]+)`")
_IMPORT = re.compile(r"mdm_montecarlo\.kernels(?:\.| import )(\w+)")


def _rows() -> list[tuple[list[str], list[str], list[str]]]:
    text = (REPO / "docs/architecture.md").read_text()
    section = text.split("## The search policy and its compiled twins", 1)[1].split("\n## ", 1)[0]
    return [
        (_NAME.findall(ref), _NAME.findall(twin), _NAME.findall(test))
        for ref, twin, test in _ROW.findall(section)
        if not ref.startswith("reference")
    ]


def test_every_pair_names_code_that_exists_and_a_test_that_reads_both() -> None:
    rows = _rows()
    assert len(rows) >= 5
    search = "".join(p.read_text() for p in sorted((REPO / "mdm_core/search").glob("*.py")))
    for refs, twins, tests in rows:
        for ref in refs:
            name = ref.removesuffix(".py").split(".")[-1]
            assert (
                re.search(rf"(def|class) {name}\b", search)
                or (REPO / "mdm_core/search" / ref).exists()
            ), ref
        for twin in twins:
            assert (REPO / "mdm_montecarlo/kernels" / twin).exists(), twin
        for test in tests:
            source = (REPO / "tests/montecarlo" / test).read_text()
            assert "mdm_core.search" in source, test
            imported = set(_IMPORT.findall(source))
            assert any(t.removesuffix(".py") in imported for t in twins), (test, twins, imported)
