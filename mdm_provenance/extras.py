"""The distribution's extras (pyproject.toml's optional dependencies) as the commands need them.

The default install is the vehicle side alone: what `companion run` and `mavlink-conformance`
import. A command that needs an extra checks, before importing any of it, that the modules the
extra brings are importable; when one is not, it says so in one line naming the `pip install`
that brings it, and exits 2 (:func:`require`).
"""

from __future__ import annotations

import sys
from importlib.util import find_spec

DISTRIBUTION = "mdm-search"

MODULES: dict[str, tuple[str, ...]] = {
    "emulator": ("numba",),
    "study": ("numba", "scipy", "matplotlib", "tqdm", "dask", "distributed", "pyarrow"),
    "ground": ("matplotlib", "shapely", "fastkml", "aiohttp", "amqtt"),
}
"""Extra -> the top-level modules its packages bring (pyproject.toml's lists, by import name;
tests/provenance/test_extras.py keeps the two in step)."""


def install_hint(extra: str) -> str:
    """The command that brings ``extra``."""
    return f"pip install '{DISTRIBUTION}[{extra}]'"


def missing_module(extra: str) -> str | None:
    """The first of ``extra``'s modules that cannot be imported here, or None."""
    for name in MODULES[extra]:
        try:
            found = find_spec(name)
        except (ImportError, ValueError):  # a broken install counts as a missing one
            found = None
        if found is None:
            return name
    return None


def refusal(command: str, extra: str) -> str | None:
    """The one line a command needing ``extra`` prints where it is not installed, or None."""
    name = missing_module(extra)
    if name is None:
        return None
    return f"{command}: needs the [{extra}] extra ({name} is not installed): {install_hint(extra)}"


def require(command: str, extra: str) -> None:
    """Exit 2 with :func:`refusal`'s line on stderr where ``extra`` is not installed."""
    line = refusal(command, extra)
    if line is not None:
        print(line, file=sys.stderr, flush=True)
        raise SystemExit(2)
