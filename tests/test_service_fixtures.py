"""The service fixtures hand out working services: headless Chromium renders a page, a broker of
the test's own takes a message, and a fleet's leftover process is found and ended."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

from selenium import webdriver
from selenium.webdriver.common.by import By

from tests.fleet_cli import processes_naming
from tests.mqtt_harness import Broker, Subscriber, publish
from tests.waiting import wait_until


def test_chromium_renders_a_page_and_runs_its_script(chromium: webdriver.Chrome) -> None:
    chromium.get(
        "data:text/html,<title>mdm</title><p id=p></p>"
        "<script>document.getElementById('p').textContent = 6 * 7</script>"
    )
    assert chromium.title == "mdm"
    assert chromium.find_element(By.ID, "p").text == "42"


def test_a_broker_of_the_tests_own_delivers_a_message(
    mosquitto: Callable[..., Broker], tmp_path: Path
) -> None:
    with mosquitto() as broker:
        sub = Subscriber(broker.port, "t/#", tmp_path / "sub.txt")
        try:
            sub.ready(broker.port, "t/probe")
            assert publish(broker.port, "t/x", "hello").returncode == 0
            wait_until(lambda: [m.payload for m in sub.messages("x")], 10.0, "t/x delivered")
        finally:
            sub.stop()


def test_fleet_processes_finds_a_process_naming_the_tests_folder(fleet_processes: Path) -> None:
    marker = fleet_processes / "still-running"
    proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)", str(marker)])
    try:
        # found once the child has exec'd (until then its command line is pytest's)
        wait_until(lambda: processes_naming(str(fleet_processes)), 10.0,
                   "the child in /proc with its command line", until=lambda p: proc.pid in p)  # fmt: skip
    finally:
        proc.kill()
        proc.wait()
    assert not processes_naming(str(fleet_processes))
