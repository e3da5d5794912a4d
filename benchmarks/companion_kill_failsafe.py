"""`kill -9` of `companion run` mid-search on a real autopilot (SITL), with the autopilot's own
companion-loss failsafe set by hand: the time from the kill to RTL and the end state, seen on
the autopilot's second link (tests/companion/sitl_observer.py), never from the companion.

    .venv/bin/python benchmarks/companion_kill_failsafe.py arducopter|px4 [pymavlink|mavsdk]

ArduCopter: the GCS failsafe watching the companion (``FS_GCS_ENABLE 1`` = RTL,
``MAV_GCS_SYSID 245``: the companion's own system id, ``FS_GCS_TIMEOUT 5``), as boot defaults.
PX4: ``COM_OBL_RC_ACT 3`` (offboard loss -> Return), set on the GCS link after boot.
Run it under ``flock /tmp/mdm-heavy.lock`` on a shared machine (fixed SITL ports)."""

from __future__ import annotations

import os
import struct
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MAVLINK20", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from tests import sitl
from tests.companion.sitl_observer import Observer
from tests.companion.test_sitl_flights import ARDUCOPTER, PX4, Companion, _profile

ARDUCOPTER_FAILSAFE = "FS_GCS_ENABLE 1\nMAV_GCS_SYSID 245\nFS_GCS_TIMEOUT 5\n"


def main(kind: str, backend: str) -> int:
    ap = ARDUCOPTER if kind == "arducopter" else PX4
    tmp = Path(tempfile.mkdtemp(prefix="kill9-"))
    defaults = None
    if ap is ARDUCOPTER:
        defaults = tmp / "failsafe.parm"
        defaults.write_text(ARDUCOPTER_FAILSAFE)
    inst = sitl.start(ap.kind, tmp / "sitl", speedup=ap.speedup, defaults=defaults)
    obs = Observer(inst.observer_url, inst.sysid)
    comp = None
    try:
        if ap is PX4:
            time.sleep(8)
            value = struct.unpack("<f", struct.pack("<i", 3))[0]  # PX4 sends integers bytewise
            for _ in range(3):
                obs._conn.mav.param_set_send(
                    inst.sysid, 1, b"COM_OBL_RC_ACT", value, mavlink2.MAV_PARAM_TYPE_INT32
                )
                time.sleep(0.5)
        profile = _profile(tmp / "profile.yaml", vehicles=inst.index + 1)
        comp = Companion(tmp, profile, inst.index, inst.companion_url, backend, duration=600.0)
        start = time.monotonic()
        while not (
            (t := obs.snapshot()).armed
            and t.mode == ap.guided_custom
            and t.alt >= 20
            and t.distance >= 150
        ):
            if time.monotonic() - start > 240:
                print(f"never searching: {obs.snapshot()}\n{comp.output()[-2000:]}")
                return 1
            time.sleep(0.2)
        boot = obs.snapshot().boot_s
        comp.kill()
        killed = time.monotonic()
        rtl: tuple[float, float] | None = None
        modes: list[int] = []
        while time.monotonic() - killed < 150:
            t = obs.snapshot()
            if t.mode not in modes:
                modes.append(t.mode)
            if rtl is None and t.mode == ap.rtl_custom:
                rtl = (time.monotonic() - killed, t.boot_s - boot)
            if t.landed_state == 1 and not t.armed:
                break
            time.sleep(0.1)
        t = obs.snapshot()
        when = "never" if rtl is None else f"{rtl[0]:.1f} wall s / {rtl[1]:.1f} vehicle s"
        texts = [x for x in t.texts if "ailsafe" in x]
        print(
            f"{kind} {backend}: modes after the kill {modes}; RTL after {when}; end "
            f"armed={t.armed} landed_state={t.landed_state}; failsafe texts {texts}"
        )
        return 0 if rtl is not None and t.landed_state == 1 and not t.armed else 1
    finally:
        if comp is not None:
            comp.kill()
        obs.close()
        inst.stop()


if __name__ == "__main__":
    args = sys.argv[1:]
    if (
        not args
        or args[0] not in ("arducopter", "px4")
        or args[1:] not in ([], ["pymavlink"], ["mavsdk"])
    ):
        print(__doc__, file=sys.stderr)
        raise SystemExit(2)
    raise SystemExit(main(args[0], args[1] if len(args) > 1 else "pymavlink"))
