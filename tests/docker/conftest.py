"""The images every docker test runs, built once per session on the local Debian base; docker
tests skip where no Docker engine (or no Compose v2) answers, saying so."""

from __future__ import annotations

import time

import pytest

from tests.docker import engine
from tests.docker.engine import ROOT, docker
from tests.docker.stack import BROKER_IMAGE
from tests.services import missing

IMAGE = "mdm-search:latest"
BUILD_STAGE = "mdm-search-build:latest"


def _timed(what: str, *args: str) -> None:
    start = time.monotonic()
    docker(*args)
    print(f"{what}: {time.monotonic() - start:.1f} s")


@pytest.fixture(scope="session")
def docker_images() -> None:
    """mdm-search and the Debian-packaged broker, built on the local Debian base, once per
    session (every docker test uses these two images)."""
    reason = engine.missing_engine()
    if reason is not None:
        missing(reason)
    start = time.monotonic()
    base = engine.ensure_base_image()
    print(f"base image {base}: {time.monotonic() - start:.1f} s")
    _timed("broker image", "build", "--force-rm", "--network=host", "--build-arg", f"BASE={base}",
           "-t", BROKER_IMAGE, str(ROOT / "docker" / "mosquitto"))  # fmt: skip
    start = time.monotonic()
    wheels = engine.wheelhouse()
    print(f"wheels: {time.monotonic() - start:.1f} s")
    with engine.serve_dir(wheels) as url:
        build = ["build", "--force-rm", "--network=host", "--build-arg", f"BASE={base}",
                 "--build-arg", "PIP_NO_INDEX=1", "--build-arg", f"PIP_FIND_LINKS={url}",
                 "-f", str(ROOT / "docker" / "Dockerfile")]  # fmt: skip
        # the build stage tagged too: untagged, the prune below would take the layers the next
        # build's cache needs (the dependencies' install)
        _timed("mdm-search build stage", *build, "--target=build", "-t", BUILD_STAGE, str(ROOT))
        _timed("mdm-search image", *build, "-t", IMAGE, str(ROOT))
    # the images these builds replaced would pile up run by run
    docker("image", "prune", "-f", "--filter", "label=org.opencontainers.image.title=mdm-search")
    size = int(docker("image", "inspect", "-f", "{{.Size}}", IMAGE).stdout)
    print(f"mdm-search image: {size / 1e6:.0f} MB")
