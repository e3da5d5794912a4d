"""Whether each outside service is here, named when it is not; a missing one skips a test, or
fails it under CI=true."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from tests import services
from tests.mqtt_harness import free_port
from tests.services import in_ci, missing


@pytest.mark.parametrize(
    ("value", "ci"), [("true", True), ("1", True), ("TRUE", True), ("", False), ("false", False)]
)
def test_ci_is_recognised_from_the_ci_variable(
    value: str, ci: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("CI", value)
    assert in_ci() is ci


def test_a_missing_service_skips_naming_it_and_fails_instead_under_ci(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.delenv("CI", raising=False)
    with pytest.raises(pytest.skip.Exception, match="no broker on port 1"):
        missing("no broker on port 1")
    monkeypatch.setenv("CI", "true")
    with pytest.raises(pytest.fail.Exception, match="CI=true and no broker on port 1"):
        missing("no broker on port 1")


def test_no_broker_on_the_port_is_named_with_the_port(monkeypatch: pytest.MonkeyPatch) -> None:
    port = free_port()
    monkeypatch.setattr(services, "MQTT_PORT", port)
    assert f"no MQTT broker listens on 127.0.0.1:{port}" in str(services.broker_missing())


@pytest.mark.parametrize(
    ("check", "named"),
    [
        (services.chromium_missing, "no chromium on PATH"),
        (services.mosquitto_missing, "no mosquitto on PATH"),
        (services.mqtt_clients_missing, "no mosquitto_sub on PATH"),
    ],
)
def test_a_program_not_on_path_is_named(
    check: Callable[[], str | None], named: str, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))
    assert named in str(check())


def test_every_service_is_listed_with_its_state(capsys: pytest.CaptureFixture[str]) -> None:
    code = services.main()
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == list(services.SERVICES)
    missing_ones = [line for line in lines if " MISSING: " in line]
    assert code == (1 if missing_ones else 0)
