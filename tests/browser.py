"""Headless Chromium from Debian (``chromium``, ``chromium-driver``) driven by Selenium; no
browser or driver is downloaded."""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from selenium.webdriver.chrome.webdriver import WebDriver

CHROMIUM = ("/usr/bin/chromium", "chromium")
CHROMEDRIVER = ("/usr/bin/chromedriver", "chromedriver")
FLAGS = (
    "--headless=new", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
    "--disable-component-update", "--disable-sync", "--no-first-run",
    "--disable-default-apps", "--window-size=1600,1000",
)  # fmt: skip


def find(candidates: tuple[str, ...]) -> str | None:
    """The first of ``candidates`` that is an executable (a path, or a name on PATH)."""
    for c in candidates:
        found = shutil.which(c)
        if found is not None:
            return found
    return None


def in_ci() -> bool:
    """``CI=true``: a missing browser fails the test instead of skipping it."""
    return os.environ.get("CI", "").strip().lower() in ("true", "1", "yes")


def missing_parts() -> str | None:
    """What is missing to drive a browser here, else None."""
    try:
        import selenium  # noqa: F401
    except ImportError:
        return "selenium is not installed (pip install -e '.[dev]')"
    if find(CHROMIUM) is None:
        return "no chromium (apt-get install chromium)"
    if find(CHROMEDRIVER) is None:
        return "no chromedriver (apt-get install chromium-driver)"
    return None


def start(profile_dir: Path) -> WebDriver:
    """A headless Chromium with a fresh user-data dir in ``profile_dir``."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = str(find(CHROMIUM))
    for flag in (*FLAGS, f"--user-data-dir={profile_dir}"):
        options.add_argument(flag)
    return webdriver.Chrome(options=options, service=Service(executable_path=find(CHROMEDRIVER)))
