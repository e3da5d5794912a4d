"""A finished fleet run replayed on the page to its end (`companion map --web`, over the
user's own map tiles), and every emulated vehicle heard by a ground station on `companion
fleet --gcs`."""

from __future__ import annotations

import os
import re
import signal
import struct
import subprocess
import sys
import threading
import time
import zlib
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from pymavlink import mavutil

from companion.telemetry.mission_log import read_records
from tests.fleet_cli import run_fleet_cli, small_profile, start_fleet
from tests.ground.live_web.page import markers, open_page, screenshot
from tests.mqtt_harness import free_port
from tests.waiting import wait_until

if TYPE_CHECKING:
    from selenium.webdriver.chrome.webdriver import WebDriver

_URL = re.compile(r"web: (http://\S+)")


@pytest.mark.timeout(240)
def test_a_finished_run_replays_to_its_end(chromium: WebDriver, fleet_processes: Path) -> None:
    tmp_path = fleet_processes
    run = tmp_path / "run"
    done = run_fleet_cli("--profile", small_profile(tmp_path), "--out", str(run),
                         "--speedup", "50", "--duration", "150", "--quiet", timeout=180)  # fmt: skip
    assert done.returncode == 0, done.stderr
    out = tmp_path / "map.out"
    tiles, asked = _tile_server()
    with out.open("wb") as f:
        server = subprocess.Popen(
            [sys.executable, "-m", "companion.cli", "map", "--web", str(run),
             "--web-bind", "127.0.0.1:0",
             "--web-tiles", f"http://127.0.0.1:{tiles.server_port}/{{z}}/{{x}}/{{y}}.png"],
            stdout=f, stderr=subprocess.STDOUT, start_new_session=True,
        )  # fmt: skip
    try:
        m = wait_until(
            lambda: _URL.search(out.read_text()), 60, "the replay's address", context=out.read_text
        )
        assert m is not None
        open_page(chromium, m.group(1))
        wait_until(lambda: chromium.find_element("id", "replay").is_displayed(), 20, "the slider")
        end = float(chromium.find_element("id", "end").text)
        assert chromium.find_elements("css selector", "button[data-command]") == []  # read-only
        chromium.find_element("id", "speed").send_keys("x200")
        chromium.find_element("id", "play").click()
        wait_until(
            lambda: chromium.find_element("id", "at").text,
            60,
            "the replay's end",
            until=lambda at: at and float(at) >= end,
        )
        wait_until(
            lambda: chromium.find_element("id", "play").text,
            10,
            "play to stop",
            until=lambda label: label == "play",
        )
        shown = markers(chromium)
        assert sorted(shown) == [0, 1, 2]
        for i, (north, east) in shown.items():
            ticks = [r for r in read_records(run / f"mission-{i}.jsonl") if r["event"] == "tick"]
            assert (north, east) == (ticks[-1]["north"], ticks[-1]["east"]), i
        assert float(chromium.find_element("id", "clock").text) == pytest.approx(end, abs=1.0)
        # the user's tile server under the map: the browser asked it for z/x/y tiles
        assert (
            int(chromium.execute_script("return document.querySelectorAll('#tiles image').length"))
            > 0
        )
        assert asked, "no tile was asked for"
        assert all(re.fullmatch(r"/\d+/\d+/\d+\.png", p) for p in asked), asked[:5]
        screenshot(chromium, tmp_path, "replay-end")
    finally:
        os.killpg(server.pid, signal.SIGTERM)
        server.wait(20)
        tiles.shutdown()


def _tile_server() -> tuple[ThreadingHTTPServer, list[str]]:
    """A tile server on a free port answering every path with one grey 256 px PNG; the
    paths asked for."""
    asked: list[str] = []
    row = b"\x00" + b"\xc8\xc8\xc8" * 256
    chunks = [
        (b"IHDR", struct.pack(">IIBBBBB", 256, 256, 8, 2, 0, 0, 0)),
        (b"IDAT", zlib.compress(row * 256)),
        (b"IEND", b""),
    ]
    png = b"\x89PNG\r\n\x1a\n" + b"".join(
        struct.pack(">I", len(d)) + k + d + struct.pack(">I", zlib.crc32(k + d)) for k, d in chunks
    )

    class Tiles(BaseHTTPRequestHandler):
        def do_GET(self) -> None:
            asked.append(self.path)
            self.send_response(200)
            self.send_header("Content-Type", "image/png")
            self.send_header("Content-Length", str(len(png)))
            self.end_headers()
            self.wfile.write(png)

        def log_message(self, *_: object) -> None:
            pass

    server = ThreadingHTTPServer(("127.0.0.1", 0), Tiles)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server, asked


@pytest.mark.timeout(180)
def test_a_ground_station_on_the_gcs_port_hears_every_vehicle(fleet_processes: Path) -> None:
    tmp_path = fleet_processes
    port = free_port()
    gcs = mavutil.mavlink_connection(f"udpin:127.0.0.1:{port}")
    fleet = start_fleet("--profile", small_profile(tmp_path), "--out", str(tmp_path / "run"),
                        "--speedup", "10", "--duration", "100", "--quiet",
                        "--gcs", f"udpout:127.0.0.1:{port}", output=tmp_path / "fleet.out")  # fmt: skip
    heard: set[int] = set()
    positions: set[int] = set()
    try:
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline and (len(heard) < 3 or len(positions) < 3):
            msg = gcs.recv_match(blocking=True, timeout=1.0)
            if msg is None:
                continue
            if msg.get_type() == "HEARTBEAT":
                heard.add(msg.get_srcSystem())
            elif msg.get_type() == "GLOBAL_POSITION_INT":
                positions.add(msg.get_srcSystem())
    finally:
        if fleet.poll() is None:
            os.killpg(fleet.pid, signal.SIGINT)
        fleet.wait(120)
        gcs.close()
    assert heard == {1, 2, 3}, (heard, (tmp_path / "fleet.out").read_text())
    # a ground station needs the positions too: the companions left the streams on
    assert positions == {1, 2, 3}, positions
