"""The live page as a test reads and drives it through Selenium: markers, rows, commands."""

from __future__ import annotations

import asyncio
import json
import re
import shutil
import subprocess
import urllib.request
from pathlib import Path
from typing import TYPE_CHECKING, Any

import aiohttp

from tests.waiting import wait_until

if TYPE_CHECKING:
    from selenium.webdriver.chrome.webdriver import WebDriver

SHOTS = Path("/tmp/live_web_screenshots")
"""Where a copy of every screenshot goes, to be looked at after the run."""
_URL = re.compile(r"live page (http://\S+)")


def page_url(output: Path, process: subprocess.Popen[bytes], timeout: float = 60.0) -> str:
    """The live page's address as `companion fleet --web` says it."""

    def said() -> str | None:
        if process.poll() is not None:
            raise AssertionError(f"the fleet exited ({process.returncode}):\n{output.read_text()}")
        m = _URL.search(output.read_text(encoding="utf-8", errors="replace"))
        return None if m is None else m.group(1)

    return str(wait_until(said, timeout, "the fleet's live page address",
                          context=output.read_text))  # fmt: skip


def page_state(url: str) -> dict[str, Any]:
    """One snapshot of the page's WebSocket, what the page draws (no browser needed)."""

    async def first() -> dict[str, Any]:
        async with (
            aiohttp.ClientSession() as session,
            session.ws_connect(url.rstrip("/") + "/ws") as ws,
        ):
            return dict(json.loads(await ws.receive_str(timeout=10.0)))

    return asyncio.run(first())


def page_command(url: str, vehicle: int | str, name: str) -> dict[str, Any]:
    """POST ``name`` for ``vehicle`` (or "all") as the page's buttons do; the 202's body."""
    body = json.dumps({"vehicle": vehicle, "command": name}).encode()
    request = urllib.request.Request(url.rstrip("/") + "/api/command", data=body,
                                     headers={"Content-Type": "application/json"})  # fmt: skip
    with urllib.request.urlopen(request, timeout=20) as answer:
        assert answer.status == 202, answer.status
        return dict(json.loads(answer.read()))


def open_page(driver: WebDriver, url: str) -> None:
    """``url`` in a window wide enough for the map and the whole table."""
    driver.set_window_size(1600, 1000)
    driver.get(url)


def markers(driver: WebDriver) -> dict[int, tuple[float, float]]:
    """Vehicle -> (north, east) of every marker drawn."""
    found = driver.execute_script(
        "return [...document.querySelectorAll('#vehicles g.vehicle')]"
        ".map(g => [Number(g.dataset.vehicle), Number(g.dataset.north), Number(g.dataset.east)])"
    )
    return {int(v): (float(n), float(e)) for v, n, e in found}


def count(driver: WebDriver, selector: str) -> int:
    return int(driver.execute_script(f"return document.querySelectorAll({selector!r}).length"))


def cell(driver: WebDriver, vehicle: int, column: int) -> str:
    """The text of a vehicle's table cell (0 the name, 1 mode, 3 phase ...)."""
    return str(driver.execute_script(
        f"const r = document.querySelector('#team tbody tr[data-vehicle=\"{vehicle}\"]');"
        f"return r ? r.children[{column}].textContent : '';"
    ))  # fmt: skip


def command(driver: WebDriver, vehicle: int | str, name: str) -> None:
    """Click the command's button, then Confirm in the page's dialog."""
    from selenium.webdriver.common.by import By

    button = f'button[data-command="{name}"][data-vehicle="{vehicle}"]'
    driver.find_element(By.CSS_SELECTOR, button).click()
    wait_until(lambda: not driver.find_element(By.ID, "confirm").get_attribute("hidden"), 5,
               "the confirm dialog")  # fmt: skip
    driver.find_element(By.ID, "confirm-yes").click()


def screenshot(driver: WebDriver, tmp_path: Path, name: str) -> Path:
    """The page as a PNG in the test's directory, and a copy in SHOTS."""
    path = tmp_path / f"{name}.png"
    driver.save_screenshot(str(path))
    SHOTS.mkdir(exist_ok=True)
    shutil.copy(path, SHOTS / path.name)
    return path
