"""Real autopilot SITL instances (ArduCopter, PX4 SIH) for tests that fly real flight code.

The binaries are test fixtures beside the project, not part of it: they are found in
``../shared/sitl/`` next to the repository, or where ``MDM_ARDUCOPTER_SITL`` /
``MDM_PX4_SITL`` point (the folder holding ``start-arducopter`` / ``start-px4``). Without one,
tests that need it skip and say which variable to set (README "Tests").

Each instance runs in its own process group (ended by group id at teardown) and takes the first
instance index, from ``MDM_SITL_INSTANCE_BASE`` (default 0) up, whose ports are all free, so
parallel runs on one machine do not collide.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from mdm_ground.fleet.sitl_team import (
    INSTANCE_BASE_ENV,
    PX4_DRAIN_S,
    companion_link,
    ports_free,
    px4_param_set,
    sitl_ports,
)

Kind = Literal["arducopter", "px4"]

REPO = Path(__file__).resolve().parents[1]
_ENV = {"arducopter": "MDM_ARDUCOPTER_SITL", "px4": "MDM_PX4_SITL"}
_SHARED = {
    "arducopter": REPO.parent / "shared" / "sitl" / "ardupilot",
    "px4": REPO.parent / "shared" / "sitl" / "px4",
}
_SCRIPT = {"arducopter": "start-arducopter", "px4": "start-px4"}
# PX4 sends its offboard link to UDP 14540+i, and i = 10 would be the GCS port 14550.
_MAX_INSTANCE = {"arducopter": 40, "px4": 9}


def sitl_dir(kind: Kind) -> Path | None:
    """The folder holding ``kind``'s start script, or None where there is none."""
    where = os.environ.get(_ENV[kind])
    folder = Path(where) if where else _SHARED[kind]
    return folder if (folder / _SCRIPT[kind]).is_file() else None


def skip_reason(kind: Kind) -> str:
    """Why a test that needs ``kind`` cannot run here."""
    return (
        f"no {kind} SITL: set {_ENV[kind]} to the folder holding {_SCRIPT[kind]} "
        f"(looked in {os.environ.get(_ENV[kind]) or _SHARED[kind]}; README 'Tests')"
    )


@dataclass
class SitlInstance:
    """One running SITL process and the addresses a companion and an observer use."""

    kind: Kind
    index: int
    process: subprocess.Popen[bytes]
    workdir: Path

    @property
    def sysid(self) -> int:
        return self.index + 1

    @property
    def companion_url(self) -> str:
        """The vehicle's primary link: ArduCopter SERIAL0 (TCP), PX4's offboard link (UDP)."""
        return companion_link(self.kind, self.index)

    @property
    def observer_url(self) -> str:
        """A second, independent link: ArduCopter SERIAL1, PX4's GCS link (it answers the sender)."""
        if self.kind == "arducopter":
            return f"tcp:127.0.0.1:{5762 + 10 * self.index}"
        return f"udpout:127.0.0.1:{18570 + self.index}"

    def log(self) -> str:
        """What the autopilot printed so far (for a failing test's message)."""
        path = self.workdir / "sitl.log"
        return path.read_text(errors="replace")[-4000:] if path.exists() else ""

    def stop(self) -> None:
        """End the whole process group; idempotent."""
        if self.process.poll() is None:
            for sig in (signal.SIGTERM, signal.SIGKILL):
                try:
                    os.killpg(self.process.pid, sig)
                except ProcessLookupError:
                    break
                try:
                    self.process.wait(timeout=5)
                    break
                except subprocess.TimeoutExpired:
                    continue


def free_index(kind: Kind) -> int:
    """The first instance index, from ``MDM_SITL_INSTANCE_BASE`` up, whose ports are all free."""
    base = int(os.environ.get(INSTANCE_BASE_ENV, "0"))
    for index in range(base, _MAX_INSTANCE[kind] + 1):
        if ports_free(*sitl_ports(kind, index)):
            return index
    raise RuntimeError(
        f"no free {kind} SITL instance index in {base}..{_MAX_INSTANCE[kind]} "
        f"({INSTANCE_BASE_ENV}={base}; {kind} instances stop at {_MAX_INSTANCE[kind]})"
    )


def start(
    kind: Kind,
    workdir: Path,
    *,
    index: int | None = None,
    home: str | None = None,
    speedup: float | None = None,
    defaults: Path | None = None,
    battery_mah: int | None = None,
) -> SitlInstance:
    """Start one instance of ``kind`` in ``workdir`` on the first free instance index.

    ``index`` is taken as given (a test that starts its client first picks it with
    :func:`free_index`); ``home`` is ``LAT,LON,ALT[,HDG]``; ``speedup`` is ArduCopter's ``--speedup`` or PX4's
    ``PX4_SIM_SPEED_FACTOR``; ``defaults`` (an extra .parm file) and ``battery_mah`` are ArduCopter only. Returns once the process runs; readiness (GPS, EKF) is the
    caller's to await.
    """
    folder = sitl_dir(kind)
    if folder is None:
        raise FileNotFoundError(skip_reason(kind))
    if index is None:
        index = free_index(kind)
    workdir.mkdir(parents=True, exist_ok=True)
    cmd = [str(_script(kind, folder, workdir)), str(index), "--dir", str(workdir / "run")]
    if home is not None:
        cmd += ["--home", home]
    if defaults is not None:
        cmd += ["--defaults", str(defaults)]
    if battery_mah is not None:
        # A bigger pack (ArduCopter's BATT_CAPACITY, stock 3300 mAh) for tests that fly long
        # random searches: the companion ends a search below 20 % and would test the battery.
        pack = workdir / "battery.parm"
        pack.write_text(f"BATT_CAPACITY {battery_mah}\n")
        cmd += ["--defaults", str(pack)]
    env = dict(os.environ)
    if kind == "px4" and speedup is not None:
        env["PX4_SIM_SPEED_FACTOR"] = str(
            speedup
        )  # PX4's own SITL clock (SIH), not a script option
    elif speedup is not None:
        cmd += ["--speedup", str(speedup)]
    with (workdir / "sitl.log").open("wb") as out:
        process = subprocess.Popen(
            cmd, stdout=out, stderr=subprocess.STDOUT, start_new_session=True, env=env
        )
    instance = SitlInstance(kind, index, process, workdir)
    # Back only once the instance holds its ports, so the next start cannot pick the same index.
    if kind == "arducopter":
        _await_bound(instance, tcp=5760 + 10 * index)
    else:
        _await_bound(instance, udp=18570 + index)
        # an hour's pack, not SIH's stock minute (mdm_ground/fleet/sitl_team.py, PX4_DRAIN_S)
        px4_param_set(folder, index, workdir, "SIM_BAT_DRAIN", PX4_DRAIN_S)
    return instance


def _script(kind: Kind, folder: Path, workdir: Path) -> Path:
    """The start script to run. PX4's start-up scripts call its modules through ``px4-NAME``
    aliases (symlinks to ``px4``) beside the binary; where a copy of the folder lost them (plain
    3-byte files), a private copy of the folder with the aliases restored is used instead."""
    if kind == "arducopter" or os.access(folder / "bin" / "px4-param", os.X_OK):
        return folder / _SCRIPT[kind]
    private = workdir / "px4"
    (private / "bin").mkdir(parents=True, exist_ok=True)
    shutil.copy2(folder / "bin" / "px4", private / "bin" / "px4")
    for alias in (folder / "bin").glob("px4-*"):
        target = private / "bin" / alias.name
        if alias.name.endswith(".sh"):
            shutil.copy2(alias, target)
        elif not target.exists():
            target.symlink_to("px4")
    for name in ("etc", _SCRIPT[kind]):
        if not (private / name).exists():
            (private / name).symlink_to(folder / name)
    return private / _SCRIPT[kind]


def _await_bound(
    instance: SitlInstance, *, tcp: int | None = None, udp: int | None = None, timeout: float = 30.0
) -> None:
    """Wait until the instance has bound ``tcp`` / ``udp`` (seen as the port turning busy: a
    probing connection would take the autopilot's one client slot on that serial port)."""
    ports = ([tcp] if tcp else [], [udp] if udp else [])
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if instance.process.poll() is not None:
            raise RuntimeError(f"{instance.kind} SITL exited: {instance.log()}")
        if not ports_free(*ports):
            return
        time.sleep(0.2)
    instance.stop()
    raise RuntimeError(
        f"{instance.kind} SITL did not bind {ports} in {timeout} s: {instance.log()}"
    )


def main(argv: list[str] | None = None) -> int:
    """``python -m tests.sitl arducopter|px4 [--speedup X]``: one instance in the foreground,
    as the tests start it (PX4 aliases restored where needed), until SIGINT/SIGTERM."""
    import argparse
    import tempfile

    parser = argparse.ArgumentParser(prog="python -m tests.sitl", description=main.__doc__)
    parser.add_argument("kind", choices=("arducopter", "px4"))
    parser.add_argument("--speedup", type=float)
    args = parser.parse_args(argv)
    kind: Kind = args.kind
    instance = start(kind, Path(tempfile.mkdtemp(prefix=f"{kind}-")), speedup=args.speedup)
    print(f"{kind} instance {instance.index}: companion {instance.companion_url}, "
          f"observer {instance.observer_url}, sysid {instance.sysid}", flush=True)  # fmt: skip
    signal.signal(signal.SIGTERM, lambda *_: instance.stop())
    try:
        instance.process.wait()
    except KeyboardInterrupt:
        pass
    finally:
        instance.stop()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
