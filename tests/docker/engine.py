"""A Docker engine for the tests: whether one answers, a Debian base image made locally with
debootstrap (no registry needed), and prebuilt wheels served on the loopback for image builds
that cannot reach the package index themselves."""

from __future__ import annotations

import functools
import hashlib
import http.server
import re
import shutil
import subprocess
import sys
import tempfile
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
RELEASE = "bookworm"
"""Debian release of the local base: its python3 (3.11) is the one the wheels are built for."""
BASE_IMAGE = f"mdm-local/debian:{RELEASE}"
IMAGE_PYTHON = (3, 11)
DEFAULT_MIRROR = "http://deb.debian.org/debian"


def docker(
    *args: str, timeout: float = 600.0, env: dict[str, str] | None = None, check: bool = True
) -> subprocess.CompletedProcess[str]:
    """``docker ARGS``; a failure raises with the command's own output."""
    proc = subprocess.run(
        ["docker", *args], capture_output=True, text=True, timeout=timeout, env=env, check=False
    )
    if check and proc.returncode != 0:
        raise AssertionError(
            f"docker {' '.join(args)} failed ({proc.returncode}):\n"
            f"{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
        )
    return proc


def missing_engine() -> str | None:
    """Why no Docker engine with Compose v2 can be used here, or None when one can."""
    if shutil.which("docker") is None:
        return "no docker client on PATH (.ci/run installs docker.io and starts dockerd)"
    if docker("info", timeout=30, check=False).returncode != 0:
        return "no Docker engine answers `docker info` (.ci/run installs and starts one)"
    if docker("compose", "version", timeout=30, check=False).returncode != 0:
        return "no `docker compose` (Compose v2 CLI plugin; .ci/run installs one)"
    return None


def image_exists(name: str) -> bool:
    return docker("image", "inspect", name, check=False).returncode == 0


def debian_mirror(sources: Path = Path("/etc/apt")) -> str:
    """The Debian mirror apt's own sources name for ``RELEASE`` (one-line or deb822 format)."""
    files = [sources / "sources.list", *sorted((sources / "sources.list.d").glob("*"))]
    for path in files:
        if not path.is_file():
            continue
        text = path.read_text(errors="replace")
        for m in re.finditer(r"^deb\s+(?:\[[^]]*\]\s+)?(\S+)\s+(\S+)", text, re.MULTILINE):
            if m.group(2) == RELEASE:
                return m.group(1)
        for stanza in re.split(r"\n\s*\n", text):
            uris = re.search(r"^URIs:\s*(\S+)", stanza, re.MULTILINE)
            suites = re.search(r"^Suites:\s*(.+)$", stanza, re.MULTILINE)
            if uris and suites and RELEASE in suites.group(1).split():
                return uris.group(1)
    return DEFAULT_MIRROR


def ensure_base_image() -> str:
    """``BASE_IMAGE``, made once with debootstrap (minbase) and `docker import`, then reused."""
    if image_exists(BASE_IMAGE):
        return BASE_IMAGE
    if shutil.which("debootstrap") is None:
        raise AssertionError(
            f"{BASE_IMAGE} is missing and debootstrap is not installed "
            "(apt-get install debootstrap; .ci/run does)"
        )
    with tempfile.TemporaryDirectory(prefix="mdm-rootfs-") as tmp:
        rootfs = Path(tmp) / "rootfs"
        subprocess.run(
            ["debootstrap", "--variant=minbase", RELEASE, str(rootfs), debian_mirror()],
            check=True,
            capture_output=True,
            timeout=600,
        )
        # apt's package lists and caches are stale in an image: every build runs apt-get update
        for stale in ("var/lib/apt/lists", "var/cache/apt"):
            for entry in (rootfs / stale).glob("*"):
                if entry.is_file():
                    entry.unlink()
        tar = subprocess.Popen(["tar", "-C", str(rootfs), "-c", "."], stdout=subprocess.PIPE)
        docker_import = subprocess.run(
            ["docker", "import", "-", BASE_IMAGE],
            stdin=tar.stdout,
            capture_output=True,
            text=True,
            timeout=300,
            check=False,
        )
        tar.wait(timeout=60)
        if docker_import.returncode != 0 or tar.returncode != 0:
            raise AssertionError(f"docker import of {rootfs} failed: {docker_import.stderr}")
    return BASE_IMAGE


def wheelhouse() -> Path:
    """Wheels of every dependency of the package and of its build backend, built with the
    host's pip (its index and certificates) for the image's Python; kept in the user's cache,
    one folder per set of requirements, and reused."""
    if sys.version_info[:2] != IMAGE_PYTHON:
        raise AssertionError(
            f"the wheels are built by this Python ({sys.version_info[0]}.{sys.version_info[1]}) "
            f"for Debian {RELEASE}'s python3 {IMAGE_PYTHON[0]}.{IMAGE_PYTHON[1]}: run the "
            "docker tests with that Python"
        )
    # what the image's dependency layer installs: the package with its [all] extra
    requirements = subprocess.run(
        [sys.executable, str(ROOT / "docker" / "requirements.py"), str(ROOT / "pyproject.toml"),
         "all"],
        check=True, capture_output=True, text=True, timeout=60,
    ).stdout.split()  # fmt: skip
    key = hashlib.sha256("\n".join(sorted(requirements)).encode()).hexdigest()[:16]
    folder = Path.home() / ".cache" / "mdm-search" / "docker-wheels" / key
    if not (folder / "complete").exists():
        folder.mkdir(parents=True, exist_ok=True)
        subprocess.run(
            [sys.executable, "-m", "pip", "wheel", "-q", "--wheel-dir", str(folder), *requirements],
            check=True,
            capture_output=True,
            timeout=600,
        )
        (folder / "complete").write_text("\n".join(requirements) + "\n")
    return folder


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: object) -> None:
        pass


WHEELS_PORT = 38765
"""The wheel server's port where it is free: the URL is a build argument, and an unchanged one
lets the build cache keep the image's dependency layer (any free port otherwise)."""


@contextmanager
def serve_dir(directory: Path) -> Iterator[str]:
    """An HTTP server on 127.0.0.1 listing ``directory``; yields its URL."""
    handler = functools.partial(_QuietHandler, directory=str(directory))
    try:
        server = http.server.ThreadingHTTPServer(("127.0.0.1", WHEELS_PORT), handler)
    except OSError:
        server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, name="wheel-server", daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()
        thread.join(timeout=5)
