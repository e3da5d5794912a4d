"""Who may command through the page: `companion watch` bound beyond loopback refuses a command
without its token (in Chromium, and nothing reaches the broker); read-only refuses all; bad
requests get a clear error."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import urllib.error
import urllib.request
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

from tests.ground.live_web.page import command, open_page, screenshot
from tests.mqtt_harness import Message, Subscriber
from tests.waiting import wait_until

if TYPE_CHECKING:
    from selenium.webdriver.chrome.webdriver import WebDriver

_URL = re.compile(r"web: (http://\S+)")


def _watch(
    tmp_path: Path, port: int, prefix: str, *flags: str
) -> tuple[subprocess.Popen[bytes], str]:
    """`companion watch` on the broker at 127.0.0.1:``port``; its process and printed address."""
    out = tmp_path / "watch.out"
    with out.open("wb") as f:
        proc = subprocess.Popen(
            [sys.executable, "-m", "companion.cli", "watch", "--mqtt", f"127.0.0.1:{port}",
             "--mqtt-prefix", prefix, *flags],
            stdout=f, stderr=subprocess.STDOUT, start_new_session=True,
        )  # fmt: skip

    def said() -> str | None:
        assert proc.poll() is None, out.read_text()
        m = _URL.search(out.read_text())
        return None if m is None else m.group(1)

    return proc, str(wait_until(said, 60, "the watch's address", context=out.read_text))


def _post(url: str, body: bytes, token: str | None = None) -> tuple[int, dict[str, Any]]:
    headers = {"Content-Type": "application/json"}
    if token is not None:
        headers["Authorization"] = f"Bearer {token}"
    req = urllib.request.Request(url + "api/command", data=body, headers=headers, method="POST")
    try:
        with urllib.request.urlopen(req, timeout=10) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read())


def _commands(sub: Subscriber) -> list[Message]:
    return [m for m in sub.messages() if m.topic.endswith("/cmd")]


def _stop(proc: subprocess.Popen[bytes]) -> None:
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGTERM)
        proc.wait(20)


@pytest.mark.timeout(180)
def test_a_command_without_the_token_on_a_non_loopback_bind_is_refused(
    chromium: WebDriver, mqtt_broker: int, tmp_path: Path
) -> None:
    prefix = f"mdm/test-{os.getpid()}-liveweb-token"
    sub = Subscriber(mqtt_broker, f"{prefix}/#", tmp_path / "sub.txt")
    sub.ready(mqtt_broker, f"{prefix}/probe")
    proc, url = _watch(tmp_path, mqtt_broker, prefix, "--web", "0.0.0.0:0")
    try:
        token = url.partition("#token=")[2]
        assert len(token) >= 16, f"no token printed for a bind to 0.0.0.0: {url}"
        local = url.partition("#")[0].replace("0.0.0.0", "127.0.0.1")
        open_page(chromium, local)  # without the token
        wait_until(
            lambda: chromium.find_element("id", "token-box").is_displayed(),
            20,
            "the token box of a page that needs one",
        )
        command(chromium, "all", "pause")
        message = wait_until(
            lambda: chromium.find_element("id", "message").text, 20, "the refusal on the page"
        )
        assert message.startswith("refused (401): a token is required"), message
        screenshot(chromium, tmp_path, "live-token-refused")

        status, answer = _post(local, b'{"vehicle": 0, "command": "abort"}', token="x" * 20)
        assert (status, answer["error"]) == (401, "wrong token")
        assert _commands(sub) == [], "a refused command reached the broker"

        chromium.find_element("id", "token").send_keys(token)
        command(chromium, "all", "pause")
        wait_until(lambda: _commands(sub), 20, "the accepted command on the broker")
        (sent,) = _commands(sub)
        assert sent.topic == f"{prefix}/all/cmd"
        assert sent.json()["command"] == "pause"
        assert chromium.find_element("id", "message").text == ""
    finally:
        _stop(proc)
        sub.stop()


@pytest.mark.timeout(120)
def test_read_only_and_bad_requests_are_refused_with_a_clear_error(
    mqtt_broker: int, tmp_path: Path
) -> None:
    prefix = f"mdm/test-{os.getpid()}-liveweb-ro"
    sub = Subscriber(mqtt_broker, f"{prefix}/#", tmp_path / "sub.txt")
    sub.ready(mqtt_broker, f"{prefix}/probe")
    proc, url = _watch(tmp_path, mqtt_broker, prefix, "--web", "127.0.0.1:0", "--web-read-only")
    (tmp_path / "open").mkdir()
    open_proc, open_url = _watch(tmp_path / "open", mqtt_broker, prefix, "--web", "127.0.0.1:0")
    try:
        status, answer = _post(url, b'{"vehicle": 0, "command": "abort"}')
        assert status == 403
        assert "read-only" in answer["error"]
        cases = {
            b"not json": "request body: not JSON",
            b'{"vehicle": 0, "command": "fly"}': "command 'fly': expected one of",
            b'{"vehicle": -1, "command": "land"}': "vehicle -1: expected a vehicle index",
            b'{"vehicle": true, "command": "land"}': "vehicle True: expected a vehicle index",
            b'{"vehicle": 0, "command": "land", "x": 1}': "request body: expected",
        }
        for body, error in cases.items():
            status, answer = _post(open_url, body)
            assert status == 400, (body, answer)
            assert answer["error"].startswith(error), (body, answer)
        req = urllib.request.Request(
            open_url + "api/command",
            method="POST",
            data=b'{"vehicle": 0, "command": "land"}',
            headers={"Origin": "http://evil.example"},
        )
        with pytest.raises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(req, timeout=10)
        assert refused.value.code == 403
        assert _commands(sub) == [], "a refused command reached the broker"
    finally:
        _stop(proc)
        _stop(open_proc)
        sub.stop()
