"""The `mdm-montecarlo` command's entry point: refuses in one line, naming the install, where the
[study] extra is not installed, before :mod:`mdm_montecarlo.commands.cli` imports any of it."""

from __future__ import annotations

from mdm_provenance import extras


def main(argv: list[str] | None = None) -> int:
    """`mdm-montecarlo`, once the [study] extra is known to be installed."""
    extras.require("mdm-montecarlo", "study")
    from mdm_montecarlo.commands.cli import main as cli_main

    return cli_main(argv)
