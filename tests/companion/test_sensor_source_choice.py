"""Which sensor source a companion flies with: the profile's, or the flag's; mqtt needs a broker."""

from __future__ import annotations

import pytest

from companion.cli import main


def test_companion_refuses_the_mqtt_source_without_a_broker(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code = main(["run", "--profile", "paper-fixed", "--vehicle", "0", "--sensor-source", "mqtt"])
    assert code == 2
    assert "sensor source 'mqtt' reads detections from a broker" in capsys.readouterr().err
