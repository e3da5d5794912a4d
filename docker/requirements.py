"""Print the requirements of the package's install with the given extras, one a line, from
pyproject.toml alone (the extras that name the package itself, like ``all``, expanded), and the
build backend's: what the image's dependency layer installs before the sources are copied.

    python3 docker/requirements.py [pyproject.toml] EXTRA[,EXTRA...]
"""

from __future__ import annotations

import re
import sys
import tomllib
from pathlib import Path
from typing import Any


def requirements(pyproject: dict[str, Any], extras: list[str]) -> list[str]:
    """The default dependencies, those of ``extras`` (recursively) and the build backend's."""
    project = pyproject["project"]
    own = re.compile(rf"{re.escape(project['name'])}\[([^]]*)\]$")
    found: list[str] = [*project["dependencies"], *pyproject["build-system"]["requires"]]
    todo, seen = list(extras), set()
    while todo:
        extra = todo.pop()
        if extra in seen:
            continue
        seen.add(extra)
        for text in project["optional-dependencies"][extra]:
            inner = own.match(text)
            if inner:
                todo.extend(e.strip() for e in inner.group(1).split(","))
            elif text not in found:
                found.append(text)
    return found


def main(argv: list[str]) -> int:
    path = Path(argv[0]) if len(argv) == 2 else Path("pyproject.toml")
    extras = [e for e in argv[-1].split(",") if e] if argv else []
    pyproject = tomllib.loads(path.read_text())
    unknown = sorted(set(extras) - set(pyproject["project"]["optional-dependencies"]))
    if unknown:
        print(f"requirements.py: {path}: no extra {unknown[0]!r}", file=sys.stderr)
        return 2
    print("\n".join(requirements(pyproject, extras)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
