"""What a field engineer keeps: after a short search and the landing, `companion run` downloads
the autopilot's own log of the flight over MAVLink (LOG_REQUEST_LIST / LOG_REQUEST_DATA) into
the run directory and prints where it is. On stock ArduCopter (dataflash ``.bin``) and PX4 SIH
(``.ulg``): the file starts with its format's magic and is, byte for byte, a log the autopilot
wrote on its own disk (the SITL's working directory, read there by the test) as far as it was
written when asked for."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from tests import sitl
from tests.companion.sitl_observer import Observer
from tests.profile_files import levels, sensors, write_profile_with
from tests.waiting import wait_until

ON_GROUND = 1  # MAV_LANDED_STATE_ON_GROUND
LOG_WAIT_S = 60
"""Wall s of download: ArduCopter's whole .bin, the first few hundred kB of PX4's .ulg (PX4 sends
about 13 kB/s here, docs/companion.md); what came is compared with the autopilot's own file."""
KINDS = {
    # kind: speed-up, the log's suffix and magic, where the autopilot writes its logs
    "arducopter": (5.0, ".bin", b"\xa3\x95", "*.BIN"),
    "px4": (3.0, ".ulg", b"ULog\x01\x12\x35", "*.ulg"),
}


@pytest.mark.parametrize("kind", list(KINDS))
def test_the_autopilot_log_is_kept_in_the_run_directory(
    kind: sitl.Kind, sitl_start: Callable[..., sitl.SitlInstance], tmp_path: Path
) -> None:
    speedup, suffix, magic, pattern = KINDS[kind]
    inst = sitl_start(kind, speedup=speedup)
    profile = write_profile_with(
        tmp_path / "short.yaml",
        "sitl-log",
        targets=[{"north": 1500.0, "east": 1500.0}],
        fleet={"vehicles": inst.index + 1},
        sensors=sensors(300.0, 100.0),
        policy={"levels": levels(600.0, 300.0, 150.0)},
        mission={"duration": 30.0},
    )
    out = tmp_path / "run"
    out.mkdir()
    obs = Observer(inst.observer_url, inst.sysid)
    with (out / "companion.out").open("ab") as f:
        companion = subprocess.Popen(
            [sys.executable, "-m", "companion.cli", "run", "--profile", str(profile),
             "--vehicle", str(inst.index), "--connect", inst.companion_url, "--log-dir", str(out),
             "--land-wait", "600", "--flight-log-wait", str(LOG_WAIT_S), "--no-map"],
            stdout=f, stderr=subprocess.STDOUT, start_new_session=True,
            env=dict(os.environ, PYTHONUNBUFFERED="1"),
        )  # fmt: skip

    def said() -> str:
        return (out / "companion.out").read_text(errors="replace")

    try:
        wait_until(
            lambda: (
                (t := obs.snapshot()).armed_ever and t.landed_state == ON_GROUND and not t.armed
            ),
            400.0,
            "flown, landed, disarmed",
            context=lambda: said()[-3000:],
        )
        assert companion.wait(timeout=360) == 0, said()[-3000:]
    finally:
        if companion.poll() is None:
            os.killpg(companion.pid, signal.SIGKILL)
            companion.wait()
        obs.close()
    found = re.search(r"vehicle \d+: autopilot log (\S+) \((\d+) bytes\)", said())
    assert found, said()[-3000:]
    kept = Path(found.group(1))
    assert kept.parent == out
    assert kept.name == f"autopilot-{inst.index}{suffix}"
    data = kept.read_bytes()
    assert len(data) == int(found.group(2)) > 10_000
    assert data.startswith(magic)
    # one of the logs on the autopilot's disk, as far as it was written when asked for
    own = {p: p.read_bytes() for p in inst.workdir.rglob(pattern)}
    equal = [p for p, written in own.items() if written[: len(data)] == data]
    sizes = {str(p): len(b) for p, b in own.items()}
    assert equal, f"{kept} ({len(data)} bytes) is none of the autopilot's logs {sizes}"
    print(
        f"\n{kind}: autopilot log {kept} ({len(data)} bytes) is the autopilot's {equal[0]} "
        f"({len(own[equal[0]])} bytes on its disk); its logs: {sizes}"
    )
