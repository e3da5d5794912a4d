"""The vehicle side finds the ground tools through their entry point, and without them each
ground subcommand says what to install (exit 2) while `companion run` keeps its parser."""

from __future__ import annotations

import argparse

import pytest

from companion import cli, ground_tools


def test_the_installed_entry_point_gives_the_ground_commands() -> None:
    tools = ground_tools.load()
    assert not isinstance(tools, str), tools
    (sub,) = (
        a for a in cli.build_parser(tools)._actions if isinstance(a, argparse._SubParsersAction)
    )
    assert set(ground_tools.COMMANDS) | {"run", "service"} == set(sub.choices)


@pytest.mark.parametrize("command", sorted(ground_tools.COMMANDS))
def test_without_the_ground_tools_each_ground_command_names_the_install(
    command: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    why = "the ground tools are not installed (aiohttp is missing): " + ground_tools.INSTALL
    monkeypatch.setattr(ground_tools, "load", lambda: why)
    assert cli.main([command, "--profile", "paper-fixed", "--anything"]) == 2
    out = capsys.readouterr().out
    assert out == f"companion {command}: {why}\n"
    assert "pip install 'mdm-search[ground]'" in out


def test_without_the_ground_tools_run_still_parses_and_draws_no_map(
    monkeypatch: pytest.MonkeyPatch, tmp_path: object, caplog: pytest.LogCaptureFixture
) -> None:
    monkeypatch.setattr(ground_tools, "load", lambda: "not installed")
    args = cli.build_parser().parse_args(["run", "--profile", "paper-fixed", "--vehicle", "0"])
    assert args.command == "run"
    from mdm_profiles import load_profile

    with caplog.at_level("INFO", logger="companion.ground_tools"):
        ground_tools.draw_run_map(tmp_path, load_profile("paper-fixed"), 0)  # type: ignore[arg-type]
    assert "no run map drawn: not installed" in caplog.text
