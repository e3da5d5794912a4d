"""The mdm-search image carries the compiled (numba) kernels of the Monte-Carlo engine and of the
emulator: a container's first `mdm-montecarlo reproduce` or `sim-vehicle` loads every kernel
from the image's cache and compiles none (built and run on the same machine, so the same CPU).

Skipped only where no Docker engine answers; `.ci/run` installs one."""

from __future__ import annotations

import pytest

from tests.docker.conftest import IMAGE
from tests.docker.engine import docker

ENGINE_KERNELS = (
    "block_rounds.fly_rounds",
    "policy_waypoints.next_waypoints",
    "compiled_tracks._append",
    "swarm_kernels.sense",
    "swarm_kernels.spso_steps",
)


@pytest.mark.timeout(900)
def test_a_fresh_container_loads_every_kernel_from_the_image(docker_images: None) -> None:
    # 20 runs per row, not the build's 1: blocks of another size must not need other kernels
    done = docker(
        "run", "--rm", "-e", "NUMBA_DEBUG_CACHE=1", IMAGE,
        "mdm-montecarlo", "reproduce", "--runs", "20", "--workers", "1", "--no-progress",
        "--out", "/tmp/report",
        timeout=600,
    )  # fmt: skip
    log = done.stdout + done.stderr
    loaded = [line for line in log.splitlines() if "data loaded from" in line]
    saved = [line for line in log.splitlines() if "data saved to" in line]
    # The MDM engine's round loop (its step, entry times and memory kernels are compiled
    # into it), the policy's first waypoints, the targets' paths and the swarm engine.
    for kernel in ENGINE_KERNELS:
        assert any(kernel in line for line in loaded), f"{kernel} not loaded:\n{log[-3000:]}"
    assert not saved, "compiled in the container:\n" + "\n".join(saved[:20])
    assert "report: /tmp/report/report.md" in log


@pytest.mark.timeout(300)
def test_a_fresh_emulator_container_loads_its_kernels_from_the_image(docker_images: None) -> None:
    done = docker(
        "run", "--rm", "-e", "NUMBA_DEBUG_CACHE=1", IMAGE,
        "sim-vehicle", "--vehicles", "3", "--speedup", "max", "--duration", "20",
        timeout=240,
    )  # fmt: skip
    log = done.stdout + done.stderr
    saved = [line for line in log.splitlines() if "data saved to" in line]
    assert "data loaded from" in log, f"no kernel loaded from the cache:\n{log[-3000:]}"
    assert not saved, "compiled in the container:\n" + "\n".join(saved[:20])
