"""`companion fleet --sitl arducopter|px4|mixed`: start one stock SITL instance per vehicle, each
booted at its start point in the profile's site, and stop them all at the end (also after a
failure or Ctrl-C). The binaries are found as the tests find them: the folder named by
``MDM_ARDUCOPTER_SITL`` / ``MDM_PX4_SITL``, else ``../shared/sitl/{ardupilot,px4}`` from the
current directory, else beside the repository this package runs from."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import time
from contextlib import suppress
from dataclasses import dataclass
from pathlib import Path

from companion.fence_from_profile import guidance_fence, profile_frame
from companion.mission.start_point import start_point
from mdm_ground.fleet import processes
from mdm_ground.fleet.preflight import FleetInputError
from mdm_ground.fleet.vehicles_file import Autopilot, VehicleEntry
from mdm_profiles import MissionProfile

SITL_KINDS = ("arducopter", "px4", "mixed")
_ENV = {"arducopter": "MDM_ARDUCOPTER_SITL", "px4": "MDM_PX4_SITL"}
_FOLDER = {"arducopter": "ardupilot", "px4": "px4"}
_SCRIPT = {"arducopter": "start-arducopter", "px4": "start-px4"}
_MAX_INDEX = 9
"""PX4 instance I sends its offboard link to UDP 14540+I; I = 10 would be the GCS port 14550."""
INSTANCE_BASE_ENV = "MDM_SITL_INSTANCE_BASE"
_BIND_S = 30.0
ARDUCOPTER_PACK_MAH = 20000
"""BATT_CAPACITY of each ArduCopter instance: SITL's stock 3300 mAh ends a search of a few
minutes on the profile's battery_min (29 % after 300 s at Duebendorf); a rehearsal is about the
mission, so the pack is big enough for the search to end it."""
PX4_DRAIN_S = 3600
"""SIM_BAT_DRAIN of each PX4 instance (sim seconds from full to empty while armed): SIH's stock
60 s drains half the pack in the first minute of flight (and then holds at SIM_BAT_MIN_PCT
50 %), so the companion's battery reserve rule rightly ends every search within a minute
(``battery 71%: home needs 74% + 10% reserve``). An hour's pack, as for ArduCopter above."""
_PARAM_S = 30.0


@dataclass
class SitlVehicle:
    """One SITL instance flying one vehicle of the profile."""

    entry: VehicleEntry
    process: subprocess.Popen[bytes]
    log: Path

    def stop(self) -> None:
        """SIGTERM to its process group, SIGKILL after 5 s; idempotent."""
        for sig in (signal.SIGTERM, signal.SIGKILL):
            if self.process.poll() is not None:
                return
            with suppress(ProcessLookupError):
                os.killpg(self.process.pid, sig)
            with suppress(subprocess.TimeoutExpired):
                self.process.wait(timeout=5)


def _sitl_folder(kind: Autopilot) -> Path | str:
    """The folder holding ``kind``'s start script, or a line saying where it looked."""
    where = os.environ.get(_ENV[kind])
    candidates = (
        [Path(where)]
        if where
        else [
            Path.cwd().parent / "shared" / "sitl" / _FOLDER[kind],
            Path(__file__).resolve().parents[3] / "shared" / "sitl" / _FOLDER[kind],
        ]
    )
    for folder in candidates:
        if (folder / _SCRIPT[kind]).is_file():
            return folder
    looked = ", ".join(str(c) for c in candidates)
    return f"no {kind} SITL ({_SCRIPT[kind]}) in {looked}; set {_ENV[kind]} to its folder"


def sitl_folders(kinds: set[Autopilot]) -> dict[Autopilot, Path]:
    """The folder of each kind's build; one refusal naming every build that is missing."""
    found = {kind: _sitl_folder(kind) for kind in sorted(kinds)}
    missing = [why for why in found.values() if isinstance(why, str)]
    if missing:
        raise FleetInputError("--sitl: " + "; ".join(missing))
    return {kind: folder for kind, folder in found.items() if isinstance(folder, Path)}


def kinds_for(sitl: str, vehicles: list[int]) -> dict[int, Autopilot]:
    """Each vehicle's autopilot: ``mixed`` alternates ArduCopter (even) and PX4 (odd)."""
    if sitl not in SITL_KINDS:
        raise FleetInputError(f"--sitl {sitl}: one of {', '.join(SITL_KINDS)}")
    if sitl == "mixed":
        return {v: "arducopter" if k % 2 == 0 else "px4" for k, v in enumerate(vehicles)}
    kind: Autopilot = "px4" if sitl == "px4" else "arducopter"
    return dict.fromkeys(vehicles, kind)


def sitl_ports(kind: Autopilot, index: int) -> tuple[list[int], list[int]]:
    """(TCP, UDP) ports instance ``index`` of ``kind`` binds or is sent to."""
    if kind == "arducopter":
        base = 5760 + 10 * index
        return [base, base + 2, base + 3], [5501 + 10 * index]
    return [], [14540 + index, 14580 + index, 18570 + index]


def ports_free(tcp: list[int], udp: list[int]) -> bool:
    """Whether every one of these TCP and UDP ports can be bound here now."""
    for kind, ports in ((socket.SOCK_STREAM, tcp), (socket.SOCK_DGRAM, udp)):
        for port in ports:
            with socket.socket(socket.AF_INET, kind) as s:
                try:
                    s.bind(("0.0.0.0", port))
                except OSError:
                    return False
    return True


def companion_link(kind: Autopilot, index: int) -> str:
    """The vehicle's primary link: ArduCopter SERIAL0 (TCP), PX4's offboard link (UDP)."""
    return (
        f"tcp:127.0.0.1:{5760 + 10 * index}"
        if kind == "arducopter"
        else f"udpin:0.0.0.0:{14540 + index}"
    )


def observer_link(entry: VehicleEntry) -> str:
    """A second link to a team instance (ArduCopter SERIAL1, PX4's GCS link) for a ground
    station or a test: the instance index is the system id - 1."""
    index = entry.system_id - 1
    if entry.autopilot == "px4":
        return f"udpout:127.0.0.1:{18570 + index}"
    return f"tcp:127.0.0.1:{5762 + 10 * index}"


def boot_points(profile: MissionProfile, seed: int, vehicles: list[int]) -> dict[int, str]:
    """``LAT,LON,ALT`` of each vehicle's start point (where its search begins)."""
    if profile.site is None:
        raise FleetInputError(
            f"--sitl: profile {profile.name!r} has no site: SITL instances boot at the site's "
            "WGS84 start points (add a site: section, or start the instances yourself and "
            "use --vehicles-file)"
        )
    frame = profile_frame(profile)
    fence = guidance_fence(profile)
    out = {}
    for v in vehicles:
        north, east = start_point(profile, seed, v, fence)
        lat, lon, _ = frame.to_geodetic(north, east, 0.0)
        out[v] = f"{lat:.7f},{lon:.7f},{profile.origin.alt:g}"
    return out


def start_team(
    profile: MissionProfile, seed: int, vehicles: list[int], sitl: str, speedup: float, out: Path
) -> list[SitlVehicle]:
    """One instance per vehicle on free instance indices (system id = index + 1, distinct
    across ArduCopter and PX4); on any failure the ones started are stopped again."""
    first = instance_base()
    kinds = kinds_for(sitl, vehicles)
    homes = boot_points(profile, seed, vehicles)  # what was asked first, then this machine
    if not speedup > 0:
        raise FleetInputError(f"--sitl-speedup {speedup:g}: must be > 0")
    folders = sitl_folders(set(kinds.values()))
    team: list[SitlVehicle] = []
    index = first - 1
    try:
        for v in vehicles:
            kind = kinds[v]
            index = next(
                (i for i in range(index + 1, _MAX_INDEX + 1) if ports_free(*sitl_ports(kind, i))),
                -1,
            )
            if index < 0:
                raise FleetInputError(
                    f"--sitl: no free SITL instance index left for vehicle {v} "
                    f"({first}..{_MAX_INDEX}, each with its own ports)"
                )
            team.append(_start(kind, folders[kind], index, v, homes[v], speedup, out))
    except BaseException:
        for member in team:
            member.stop()
        raise
    return team


def instance_base() -> int:
    """The first SITL instance index a team may take: ``MDM_SITL_INSTANCE_BASE`` (default 0),
    so that two runs on one machine at once take indices apart."""
    raw = os.environ.get(INSTANCE_BASE_ENV, "0")
    try:
        base = int(raw)
    except ValueError:
        base = -1
    if not 0 <= base <= _MAX_INDEX:
        raise FleetInputError(
            f"{INSTANCE_BASE_ENV}={raw!r}: expected an instance index 0..{_MAX_INDEX}"
        )
    return base


def _start(
    kind: Autopilot, folder: Path, index: int, vehicle: int, home: str, speedup: float, out: Path
) -> SitlVehicle:
    workdir = out / f"sitl-{vehicle}"
    workdir.mkdir(parents=True, exist_ok=True)
    cmd = [
        str(folder / _SCRIPT[kind]),
        str(index),
        "--dir",
        str(workdir),
        "--speedup",
        f"{speedup:g}",
    ]
    if kind == "arducopter":
        pack = workdir / "rehearsal.parm"
        pack.write_text(f"BATT_CAPACITY {ARDUCOPTER_PACK_MAH}\n")
        cmd += ["--home", f"{home},0", "--defaults", str(pack)]
    else:
        cmd += ["--home", home]
    log = out / f"sitl-{vehicle}.log"
    # its own process group, and SIGTERM when the fleet dies without stopping it
    process = processes.start(cmd, log, dict(os.environ), append=False)
    entry = VehicleEntry(
        index=vehicle, link=companion_link(kind, index), system_id=index + 1, autopilot=kind
    )
    member = SitlVehicle(entry, process, log)
    # Ready to probe once it holds its link's port (a probing connection would take
    # ArduCopter's one client slot on SERIAL0 too early).
    watch = ([5760 + 10 * index], []) if kind == "arducopter" else ([], [18570 + index])
    deadline = time.monotonic() + _BIND_S
    while ports_free(*watch):
        if process.poll() is not None or time.monotonic() > deadline:
            member.stop()
            raise FleetInputError(
                f"--sitl: the {kind} SITL of vehicle {vehicle} did not start "
                f"within {_BIND_S:g} s (its output: {log})"
            )
        time.sleep(0.2)
    if kind == "px4":
        try:
            px4_param_set(folder, index, workdir, "SIM_BAT_DRAIN", PX4_DRAIN_S)
        except FleetInputError:
            member.stop()
            raise
    return member


def px4_param_set(folder: Path, index: int, workdir: Path, name: str, value: float) -> None:
    """Set parameter ``name`` of PX4 instance ``index`` through PX4's own shell client (the
    ``px4-param`` alias of its binary), retried until its server answers (within 30 s)."""
    client = workdir / "px4-param"
    if not client.exists():
        client.symlink_to(folder / "bin" / "px4")
    cmd = [str(client), "--instance", str(index), "set", name, f"{value:g}"]
    deadline = time.monotonic() + _PARAM_S
    while True:
        done = subprocess.run(cmd, capture_output=True, text=True, check=False)
        if done.returncode == 0:
            return
        if time.monotonic() > deadline:
            raise FleetInputError(
                f"--sitl: PX4 instance {index} did not take {name} {value:g}: "
                f"{(done.stdout + done.stderr).strip()[-300:]}"
            )
        time.sleep(0.5)
