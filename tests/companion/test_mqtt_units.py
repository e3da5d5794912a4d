"""The MQTT pieces without a broker: the durable outbox across restarts, command payloads,
--mqtt flags over a profile's mqtt: section, and secrets read from a variable or a file."""

from __future__ import annotations

import argparse
import asyncio
import json
import os
from pathlib import Path

import pytest

from companion.autopilots.base import FlightMode
from companion.telemetry import events
from companion.telemetry.events import LogFormatError
from companion.telemetry.mqtt.cli_args import add_mqtt_arguments, mqtt_argv, mqtt_spec
from companion.telemetry.mqtt.commands import Command, CommandError, parse_command
from companion.telemetry.mqtt.outbox import EventOutbox
from companion.telemetry.mqtt.settings import settings_for
from companion.telemetry.mqtt.vehicle_telemetry import VehicleTelemetry, cancel_and_wait
from mdm_profiles.mqtt_spec import MqttSpec


def test_outbox_numbers_events_and_a_restart_resends_only_the_unacknowledged(
    tmp_path: Path,
) -> None:
    path = tmp_path / "mqtt-outbox-0.jsonl"
    box = EventOutbox(path)
    for k in range(5):
        assert box.append({"t": float(k), "event": "level", "level": k % 2}) == k
    assert [s for s, _ in box.pending(3)] == [0, 1, 2]
    box.ack(2)
    assert [s for s, _ in box.pending(10)] == [3, 4]
    box.close()
    with path.open("a") as f:
        f.write('{"seq": 5, "t": 5.0, "ev')  # killed mid-write
    again = EventOutbox(path)
    assert [json.loads(p)["seq"] for _, p in again.pending(10)] == [3, 4]
    assert again.append({"t": 6.0, "event": "end"}) == 5
    again.close()
    lines = path.read_text().splitlines()
    assert json.loads(lines[-1]) == {
        "seq": 5,
        "t": 6.0,
        "event": "end",
    }  # not glued to the torn line


def test_a_published_durable_event_reads_back_as_its_class(tmp_path: Path) -> None:
    box = EventOutbox(tmp_path / "mqtt-outbox-3.jsonl")
    written = events.PhaseChange("paused", by="operator")
    box.append({"vehicle": 3, "t": 12.0, "event": written.NAME, **events.to_fields(written)})
    ((seq, payload),) = box.pending(1)
    box.close()
    message = json.loads(payload)
    assert (seq, message["vehicle"]) == (0, 3)
    assert events.from_message(message) == written
    assert events.from_message({"seq": 1, "vehicle": 3, "t": 1.0, "event": "tick"}) is None
    renamed = {"seq": 2, "vehicle": 3, "t": 1.0, "event": "end", "why": "battery", "found": 0}
    with pytest.raises(LogFormatError, match=r"^uav3/event: 'end' record has field 'why'"):
        events.from_message(renamed, "uav3/event")


@pytest.mark.parametrize(
    ("payload", "error"),
    [
        (b"pause", "not JSON"),
        (b'["pause"]', "expected a JSON object, got list"),
        (
            b'{"command": "takeoff"}',
            "command 'takeoff': expected one of pause, resume, abort, land",
        ),
        (b'{"command": "pause", "force": true}', "unknown field(s) force"),
        (b'{"command": "land", "id": {"a": 1}}', "id: a string or number"),
        (b"\xff\xfe", "not JSON"),
    ],
)
def test_bad_command_payloads_say_what_is_wrong(payload: bytes, error: str) -> None:
    with pytest.raises(CommandError, match=error.replace("(", r"\(").replace(")", r"\)")):
        parse_command(payload)


def test_command_with_an_id() -> None:
    assert parse_command(b'{"command": "abort", "id": 7}') == Command("abort", "7")


def _args(*argv: str) -> argparse.Namespace:
    p = argparse.ArgumentParser()
    add_mqtt_arguments(p)
    return p.parse_args(argv)


def test_no_broker_anywhere_means_no_mqtt() -> None:
    assert mqtt_spec(_args(), None) is None
    with pytest.raises(ValueError, match="need --mqtt HOST"):
        mqtt_spec(_args("--mqtt-username", "u"), None)


def test_flags_override_the_profile_section_and_pass_through_to_a_fleet() -> None:
    profile = MqttSpec(host="broker.local", port=8883, username="uav{vehicle}", state_rate=1.0)
    args = _args("--mqtt", "10.0.0.5:1884", "--mqtt-state-rate", "4", "--mqtt-insecure",
                 "--mqtt-prefix", "mdm/field-1")  # fmt: skip
    spec = mqtt_spec(args, profile)
    assert spec is not None
    assert (spec.host, spec.port, spec.username, spec.state_rate) == (
        "10.0.0.5",
        1884,
        "uav{vehicle}",
        4.0,
    )
    assert spec.topic_prefix == "mdm/field-1"
    assert spec.tls is not None
    assert spec.tls.insecure
    assert mqtt_spec(_args(*mqtt_argv(args)), profile) == spec
    assert mqtt_spec(_args("--mqtt", "[::1]"), None) == MqttSpec(host="::1")
    assert mqtt_spec(_args("--mqtt", "[::1]:1885"), None) == MqttSpec(host="::1", port=1885)
    assert mqtt_spec(_args("--mqtt", "fe80::1"), None) == MqttSpec(host="fe80::1")


@pytest.mark.parametrize(
    ("argv", "error"),
    [
        (("--mqtt", "host:99999"), "port must be a number 1-65535"),
        (("--mqtt", ":1883"), "no host"),
        (("--mqtt", "h", "--mqtt-prefix", "mdm/#"), "topic_prefix 'mdm/#'"),
        (("--mqtt", "h", "--mqtt-password-env", "X"), "a password needs a username"),
    ],
)
def test_bad_flags_fail_with_a_clear_message(argv: tuple[str, ...], error: str) -> None:
    with pytest.raises(ValueError, match=error):
        mqtt_spec(_args(*argv), None)


def test_password_from_a_variable_or_a_file_per_vehicle(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("PW_UAV3", "s3cret")
    by_env = settings_for(
        MqttSpec(host="h", username="uav{vehicle}", password_env="PW_UAV{vehicle}"), 3
    )
    assert (by_env.username, by_env.password) == ("uav3", "s3cret")
    assert "s3cret" not in repr(by_env)
    (tmp_path / "uav2.pw").write_text("from-file\n")
    spec = MqttSpec(host="h", username="u", password_file=str(tmp_path / "uav{vehicle}.pw"))
    assert settings_for(spec, 2).password == "from-file"
    with pytest.raises(ValueError, match=r"mqtt.password_file .*uav5.pw: No such file"):
        settings_for(spec, 5)
    with pytest.raises(ValueError, match="environment variable PW_UAV4 is not set"):
        settings_for(MqttSpec(host="h", username="u", password_env="PW_UAV{vehicle}"), 4)
    with pytest.raises(ValueError, match=r"mqtt\.tls\.ca /nowhere/ca\.crt: no such file"):
        settings_for(MqttSpec.model_validate({"host": "h", "tls": {"ca": "/nowhere/ca.crt"}}), 0)


def test_a_task_whose_wait_for_lost_the_cancellation_still_ends() -> None:
    """The cause of a companion that never exited: a publishing loop whose wait completes in
    the loop iteration it is cancelled in (Python 3.11's wait_for then drops the cancel)."""

    async def main() -> None:
        published = asyncio.Event()

        async def publishing() -> None:
            while True:
                await asyncio.wait_for(published.wait(), 10)
                published.clear()
                await asyncio.sleep(0.05)

        task = asyncio.create_task(publishing())
        await asyncio.sleep(0.01)
        published.set()  # the wait completes in the iteration of the cancel below
        stopping = asyncio.create_task(cancel_and_wait(task))
        await asyncio.wait({stopping}, timeout=5.0)  # never cancels on its own
        ended = task.done()
        stopping.cancel()
        task.cancel()
        assert ended, "the task ran on after its cancellation was lost"
        assert task.cancelled()

    asyncio.run(main())


class _Landed:
    """A vehicle that has finished: what the telemetry reads of it on its way out."""

    def operator_pause(self) -> str | None:
        return "done"

    def operator_resume(self) -> str | None:
        return "done"

    def operator_end(self, action: FlightMode, reason: str) -> str | None:
        return "done"

    def snapshot(self) -> dict[str, object]:
        return {"phase": "done"}

    def emit(self, event: str, **fields: object) -> None:
        pass


def test_leaving_ends_a_state_loop_that_lost_its_cancellation(tmp_path: Path) -> None:
    """The companion that did not exit in CI (killed by the fleet 30 s after its mission): its
    state loop lost the one cancellation a TaskGroup passes to its children (wait_for inside a
    publish), and only that one; each MQTT loop is now cancelled and waited for by itself."""
    spec = MqttSpec(host="127.0.0.1", topic_prefix=f"mdm/test-lost-cancel-{os.getpid()}")
    telemetry = VehicleTelemetry.open(spec, profile_name="t", vehicle=0, log_dir=tmp_path)
    lost: list[float] = []

    async def state_loop_losing_one_cancel() -> None:
        while True:
            try:
                await asyncio.sleep(0.05)
            except asyncio.CancelledError:
                if lost:
                    raise
                lost.append(asyncio.get_running_loop().time())

    telemetry._publish_state = state_loop_losing_one_cancel  # type: ignore[method-assign]

    async def main() -> None:
        async def fly() -> None:
            async with telemetry.running(_Landed()):
                await asyncio.sleep(0.3)

        await asyncio.wait_for(fly(), 15.0)

    asyncio.run(main())  # before: TimeoutError, the loop ran on
    assert len(lost) == 1, "the state loop was never cancelled"
