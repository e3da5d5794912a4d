"""``--version`` for the project's commands: printed on request only, so the git calls it
makes cost nothing on an ordinary start."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import Any

from mdm_provenance.record import version_text


class _VersionAction(argparse.Action):
    def __init__(self, option_strings: Sequence[str], dest: str, **kwargs: Any) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: str | Sequence[Any] | None,
        option_string: str | None = None,
    ) -> None:
        print(version_text(parser.prog))  # to stdout, as argparse's own "version" action
        parser.exit()


def add_version_flag(parser: argparse.ArgumentParser) -> None:
    """``--version``: the program, the package version and, in a git checkout, the commit."""
    parser.add_argument(
        "--version", action=_VersionAction, help="print the version and git commit, then exit"
    )
