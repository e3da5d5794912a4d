"""The page's pieces without a browser or broker: address flags, access rules, and what the
team's messages make of the state the page draws."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from companion.telemetry.mqtt.channel import Received
from companion.telemetry.mqtt.settings import MqttSettings
from mdm_ground.fleet.gcs import parse_gcs
from mdm_ground.live_web.access import AccessError, resolve_access
from mdm_ground.live_web.cli_args import parse_web
from mdm_ground.live_web.fleet_state import TRACK_KEPT, CommandOutcome, FleetState, Sent
from mdm_ground.live_web.mqtt_feed import MqttFeed
from mdm_ground.live_web.replay import Replay
from tests.profile_files import profile_with


def _state() -> FleetState:
    return FleetState(profile_with("units"), show_targets=True, stale_after=5.0)


@pytest.mark.parametrize(
    ("value", "expected"),
    [("8765", ("127.0.0.1", 8765)), ("0.0.0.0:80", ("0.0.0.0", 80)), ("[::1]:0", ("::1", 0))],
)
def test_web_addresses_are_read(value: str, expected: tuple[str, int]) -> None:
    assert parse_web(value) == expected


@pytest.mark.parametrize("value", ["::1:80", "host:", "host:70000", ":80", "a:b"])
def test_bad_web_addresses_are_refused_naming_the_flag(value: str) -> None:
    with pytest.raises(ValueError, match="--web"):
        parse_web(value)


@pytest.mark.parametrize(
    "value", ["udp:1.2.3.4:5", "udpout:host.local:5", "udpout:1.2.3.4:0", "udpout:1.2.3.4"]
)
def test_bad_gcs_addresses_are_refused_naming_the_flag(value: str) -> None:
    with pytest.raises(ValueError, match="--gcs"):
        parse_gcs(value)


def test_loopback_is_open_and_any_other_bind_gets_a_token(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("MDM_WEB_TOKEN", raising=False)
    local, made = resolve_access("127.0.0.1", read_only=False, token_file=None)
    assert (local.token, made) == (None, False)
    local.check_command(None)
    wide, made = resolve_access("0.0.0.0", read_only=False, token_file=None)
    assert made
    assert wide.token is not None
    with pytest.raises(AccessError, match="a token is required") as e:
        wide.check_command(None)
    assert e.value.status == 401
    wide.check_command(wide.token)
    (tmp_path / "token").write_text("short\n")
    with pytest.raises(ValueError, match=r"--web-token-file .* at least 16"):
        resolve_access("0.0.0.0", read_only=False, token_file=tmp_path / "token")
    monkeypatch.setenv("MDM_WEB_TOKEN", "t" * 20)
    env, made = resolve_access("0.0.0.0", read_only=False, token_file=None)
    assert (env.token, made) == ("t" * 20, False)
    with pytest.raises(AccessError, match="read-only"):
        resolve_access("0.0.0.0", read_only=True, token_file=None)[0].check_command("t" * 20)


def test_state_messages_move_the_vehicle_and_bad_fields_change_nothing() -> None:
    s = _state()
    s.on_state(
        0,
        {
            "t": 10.0,
            "north": 100.0,
            "east": 200.0,
            "alt": 30.0,
            "mode": "OFFBOARD",
            "armed": True,
            "phase": "search",
            "level": 1,
            "ci": 0.5,
            "found": 0,
            "battery": 87.0,
        },
        wall=1000.0,
    )
    s.on_state(
        0,
        {
            "t": math.nan,
            "north": math.inf,
            "east": 1.0,
            "alt": "high",
            "armed": "yes",
            "level": True,
        },
        wall=1001.0,
    )
    (v,) = s.snapshot(1002.0)["vehicles"]
    assert (v["north"], v["east"], v["alt"], v["armed"], v["level"]) == (
        100.0,
        200.0,
        30.0,
        True,
        1,
    )
    assert (v["battery"], v["age"], v["stale"], v["t"]) == (87.0, 1.0, False, 10.0)
    assert s.snapshot(1006.5)["vehicles"][0]["stale"]  # silent for 5.5 s > 5 s
    s.on_status(0, {"state": "offline"}, wall=1007.0)
    assert s.snapshot(1007.0)["vehicles"][0]["stale"]


def test_tracks_go_out_once_per_page() -> None:
    s, sent = _state(), Sent()
    for k in range(3):
        s.on_state(1, {"north": 10.0 * k, "east": 0.0}, wall=0.0)
    first = s.snapshot(0.0, sent)["vehicles"][0]
    s.on_state(1, {"north": 31.0, "east": 0.0}, wall=0.0)
    s.on_state(1, {"north": 32.0, "east": 0.0}, wall=0.0)  # under 5 m from the last point kept
    second = s.snapshot(0.0, sent)["vehicles"][0]
    assert (first["track_from"], len(first["track"])) == (0, 3)
    assert (second["track_from"], second["track"]) == (3, [(31.0, 0.0)])


def test_a_track_keeps_its_newest_points_and_a_late_page_gets_those_alone() -> None:
    s, early = _state(), Sent()
    s.on_state(1, {"north": 0.0, "east": 0.0}, wall=0.0)
    s.snapshot(0.0, early)
    for k in range(1, 3 * TRACK_KEPT):
        s.on_state(1, {"north": 10.0 * k, "east": 0.0}, wall=0.0)
    late = s.snapshot(0.0)["vehicles"][0]
    assert TRACK_KEPT <= len(late["track"]) < 2 * TRACK_KEPT
    assert late["track_from"] + len(late["track"]) == 3 * TRACK_KEPT
    assert late["track"][-1] == (10.0 * (3 * TRACK_KEPT - 1), 0.0)
    # a page that held the first point gets the kept ones, numbered from where they start
    caught_up = s.snapshot(0.0, early)["vehicles"][0]
    assert (caught_up["track_from"], caught_up["track"]) == (late["track_from"], late["track"])


def test_the_event_log_has_each_event_once_per_page_and_the_pages_own_lines() -> None:
    s, page = _state(), Sent()
    s.on_status(0, {"vehicle": 0, "state": "online", "clean": True}, wall=1000.0)
    s.on_event(0, {"seq": 0, "t": 3.0, "event": "phase", "phase": "search"}, wall=1000.0)
    s.on_event(0, {"seq": 1, "t": 4.0, "event": "tick", "north": 1.0, "east": 1.0}, 1000.0)
    s.on_event(0, {"seq": 2, "t": 70.5, "event": "detection", "north": 1499.6, "east": 20.0,
                   "level": 0}, wall=1001.0)  # fmt: skip
    first = s.snapshot(1001.0, page)["log"]
    assert [(e["t"], e["vehicle"], e["kind"]) for e in first] == [
        (0.0, 0, "status"), (3.0, 0, "phase"), (70.5, 0, "detection"),
    ]  # fmt: skip
    assert first[2]["text"] == "detection at N 1500 E 20, level 1"
    outcome = CommandOutcome("abc", "abort", "uav0", 1002.0)
    s.sent(outcome)
    s.on_event(0, {"seq": 3, "t": 71.0, "event": "command", "command": "abort", "id": "abc"},
               wall=1002.0)  # fmt: skip
    s.on_event(0, {"seq": 4, "t": 72.0, "event": "confirmation", "north": 1500.0,
                   "east": 20.0, "level": 1, "found": 1}, wall=1002.0)  # fmt: skip
    second = s.snapshot(1002.0, page)["log"]
    assert [(e["n"], e["kind"], e["severity"]) for e in second] == [
        (3, "sent", "info"), (4, "command", "info"), (5, "confirmation", "good"),
    ]  # fmt: skip
    assert second[0]["text"] == "operator sent abort to uav0 (id abc)"
    assert second[1]["text"] == "command abort accepted (id abc)"
    # silent past --stale-after: one line, and one when it is heard again
    assert [e["text"] for e in s.snapshot(1010.0, page)["log"]] == ["silent for 8 s (stale)"]
    assert s.snapshot(1011.0, page)["log"] == []
    s.on_state(0, {"t": 80.0}, wall=1012.0)
    assert [e["text"] for e in s.snapshot(1012.0, page)["log"]] == ["heard again"]
    s.on_status(0, {"vehicle": 0, "state": "offline", "clean": False}, wall=1013.0)
    (gone,) = s.snapshot(1013.0, page)["log"]
    assert (gone["severity"], gone["text"]) == (
        "alert", "companion gone without a goodbye (the broker's last will)",
    )  # fmt: skip


def test_command_answers_and_refusals_reach_their_command() -> None:
    s = _state()
    s.sent(CommandOutcome("a1", "pause", "all", 0.0))
    s.on_event(0, {"t": 5.0, "event": "command", "command": "pause", "id": "a1"}, wall=0.0)
    s.on_event(1, {"t": 5.0, "event": "command", "command": "pause", "id": "a1"}, wall=0.0)
    s.on_event(
        1,
        {
            "t": 5.0,
            "event": "error",
            "source": "command",
            "error": "not searching",
            "payload": '{"command": "pause", "id": "a1"}',
        },
        wall=0.0,
    )
    s.on_event(1, {"t": 6.0, "event": "command", "command": "pause", "id": "other"}, wall=0.0)
    (c,) = s.snapshot(0.0)["commands"]
    assert c["answers"] == {"0": "accepted", "1": "refused: not searching"}


def test_tnc_counts_real_targets_within_the_confirmation_radius() -> None:
    s = _state()  # real target at 1500,1500; false one at 600,2400; confirmation radius 50 m
    s.on_event(
        0,
        {
            "t": 1.0,
            "event": "confirmation",
            "north": 1530.0,
            "east": 1500.0,
            "level": 1,
            "found": 1,
        },
        wall=0.0,
    )
    s.on_event(
        1,
        {"t": 2.0, "event": "confirmation", "north": 600.0, "east": 2400.0, "level": 1, "found": 1},
        wall=0.0,
    )
    assert s.tnc() == 1
    assert len(s.snapshot(0.0)["confirmations"]) == 2


def test_a_directory_without_mission_logs_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"no mission-I\.jsonl"):
        Replay(tmp_path, profile_with("units"), show_targets=True)


def test_an_event_delivered_twice_counts_once() -> None:
    s = _state()
    feed = MqttFeed(MqttSettings("127.0.0.1"), "mdm/units", s)  # not connected: fed by hand
    event = b'{"seq": 7, "vehicle": 2, "t": 3.0, "event": "detection", "north": 1.0, "east": 2.0, "level": 0}'
    for payload in (event, event, b"not json", b"[1]"):
        feed._on_message(Received("mdm/units/uav2/event", payload, retained=False))
    assert len(s.detections) == 1
    assert feed.refused == 2


def test_watchs_embedded_broker_flags_are_refused_with_a_broker_and_a_taken_port_named(
    capsys: pytest.CaptureFixture[str],
) -> None:
    import socket

    from companion import cli

    assert cli.main(["watch", "--mqtt", "127.0.0.1", "--broker-bind", "1884"]) == 2
    assert (
        "--broker-bind and --broker-accounts are the embedded broker's" in capsys.readouterr().err
    )
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        assert cli.main(["watch", "--web", "0", "--broker-bind", f"127.0.0.1:{port}"]) == 2
    said = capsys.readouterr().err
    assert f"embedded MQTT broker: cannot listen on 127.0.0.1:{port}" in said, said
