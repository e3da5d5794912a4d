"""The live page's delay and its server's CPU share during a fleet run.

    .venv/bin/python benchmarks/live_web_delay.py [--broker embedded|mosquitto] [--vehicles 12]
        [--speedup 1] [--seconds 120]

Needs Debian's chromium + chromedriver, and for ``--broker mosquitto`` (the default) Mosquitto on
127.0.0.1:1883. Runs `companion fleet --web 127.0.0.1:0` on paper-fixed, with
``--mqtt 127.0.0.1:1883`` or without (the page's embedded broker; the subscriber below takes the
run's ``monitor`` account), opens the page in headless Chromium and, beside it, subscribes to
the team's state topic with paho (independent of the page's own MQTT code). Printed:

- per vehicle position change seen on the page: the wall time since the state message carrying
  that position reached the independent subscriber (MQTT -> server -> WebSocket -> DOM), as
  median, 95th percentile and maximum; and the interval between two state messages of a
  vehicle (how old a position can already be when it leaves the companion);
- the `companion watch` process's CPU seconds over the measured window and its share of one
  core (with the embedded broker: the page server and the broker), beside the whole fleet's
  (emulator, companions, page server).

Wall-clock figures on a shared host: print `uptime` beside them.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import paho.mqtt.client as mqtt
from paho.mqtt.enums import CallbackAPIVersion
from selenium import webdriver
from selenium.webdriver.chrome.service import Service

_URL = re.compile(r"live page (http://\S+)")
_BROKER = re.compile(r"embedded MQTT broker (\S+):(\d+) ")
_WATCH_JS = """
window.__moves = [];
const shown = {};
new MutationObserver((records) => {
  for (const r of records) {
    const g = r.target;
    if (!g.dataset || g.dataset.vehicle === undefined || r.attributeName !== 'transform') continue;
    const where = g.dataset.north + ',' + g.dataset.east;
    if (shown[g.dataset.vehicle] === where) continue;  // set again, not moved
    shown[g.dataset.vehicle] = where;
    window.__moves.push([Date.now() / 1000, Number(g.dataset.vehicle),
                         Number(g.dataset.north), Number(g.dataset.east)]);
  }
}).observe(document.getElementById('vehicles'), {attributes: true, subtree: true});
"""


def _chromium(profile: Path) -> webdriver.Chrome:
    """Debian's headless Chromium and chromedriver (nothing downloaded), a fresh profile."""
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for flag in (
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--window-size=1600,1000",
        f"--user-data-dir={profile}",
    ):
        options.add_argument(flag)
    return webdriver.Chrome(options=options, service=Service("/usr/bin/chromedriver"))


def _cpu_s(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _pids(text: str) -> dict[int, str]:
    """Processes whose command line holds ``text``: pid -> command line."""
    found = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                cmd = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode()
            except OSError:
                continue
            if text in cmd and "live_web_delay" not in cmd:
                found[int(entry.name)] = cmd
    return found


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--vehicles", type=int, default=12)
    ap.add_argument("--speedup", type=float, default=1.0)
    ap.add_argument("--seconds", type=float, default=120.0, help="measured wall window")
    ap.add_argument("--broker", choices=("mosquitto", "embedded"), default="mosquitto")
    args = ap.parse_args()
    embedded = args.broker == "embedded"
    # the embedded broker is the run's own: the default prefix, as its ACL wants
    prefix = "mdm/paper-fixed" if embedded else f"mdm/bench-liveweb-{os.getpid()}"
    work = Path(tempfile.mkdtemp(prefix="live-web-bench-"))
    arrivals: dict[tuple[int, float, float], float] = {}
    intervals: list[float] = []
    last: dict[int, float] = {}
    lock = threading.Lock()

    def on_message(_c: object, _u: object, msg: mqtt.MQTTMessage) -> None:
        now = time.time()
        s = json.loads(msg.payload)
        if "north" not in s:
            return
        with lock:
            arrivals.setdefault((int(s["vehicle"]), s["north"], s["east"]), now)
            if s["vehicle"] in last:
                intervals.append(now - last[s["vehicle"]])
            last[s["vehicle"]] = now

    sub = mqtt.Client(CallbackAPIVersion.VERSION2)
    sub.on_message = on_message
    duration = args.seconds * args.speedup + 600.0
    out = work / "fleet.out"
    with out.open("wb") as f:
        fleet = subprocess.Popen(
            [sys.executable, "-m", "companion.cli", "fleet", "--profile", "paper-fixed",
             "--vehicles", str(args.vehicles), "--speedup", str(args.speedup),
             "--duration", str(duration), "--out", str(work / "run"), "--quiet",
             "--web", "127.0.0.1:0",
             *([] if embedded else ["--mqtt", "127.0.0.1:1883", "--mqtt-prefix", prefix])],
            stdout=f, stderr=subprocess.STDOUT, start_new_session=True,
        )  # fmt: skip
    driver = None
    try:
        deadline = time.monotonic() + 120
        while (m := _URL.search(out.read_text())) is None:
            if time.monotonic() > deadline or fleet.poll() is not None:
                raise SystemExit(f"no live page:\n{out.read_text()}")
            time.sleep(0.5)
        if embedded:
            host, port = _BROKER.search(out.read_text()).groups()  # type: ignore[union-attr]
            monitor = (work / "run" / "broker-accounts" / "monitor.pw").read_text().strip()
            sub.username_pw_set("monitor", monitor)
            sub.connect(host, int(port))
        else:
            sub.connect("127.0.0.1", 1883)
        sub.subscribe(f"{prefix}/+/state")
        sub.loop_start()
        driver = _chromium(work / "chromium")
        driver.get(m.group(1))
        time.sleep(5)
        driver.execute_script(_WATCH_JS)
        # the page names the run (its broker's accounts) or the prefix (--mqtt-prefix)
        team = _pids(str(work / "run")) | ({} if embedded else _pids(prefix))
        (watch,) = [p for p, cmd in team.items() if "companion.cli watch" in cmd]
        cpu0 = {p: _cpu_s(p) for p in team}
        t0 = time.monotonic()
        time.sleep(args.seconds)
        window = time.monotonic() - t0
        cpu = {p: _cpu_s(p) - c for p, c in cpu0.items()}
        moves = driver.execute_script("return window.__moves")
    finally:
        if driver is not None:
            driver.quit()
        if fleet.poll() is None:
            os.killpg(fleet.pid, signal.SIGINT)
            time.sleep(5)
            os.killpg(fleet.pid, signal.SIGINT)
            fleet.wait(60)
        if not embedded:
            for i in range(args.vehicles):  # leave no retained status on the broker
                sub.publish(f"{prefix}/uav{i}/status", b"", qos=1, retain=True).wait_for_publish(5)
        sub.loop_stop()
    with lock:
        delays = [t - arrivals[(v, n, e)] for t, v, n, e in moves if (v, n, e) in arrivals]
    delays.sort()
    load = os.getloadavg()
    print(
        f"broker {args.broker}: {args.vehicles} vehicles, speed-up {args.speedup:g}, "
        f"window {window:.0f} s wall; "
        f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}"
    )
    print(f"page position updates {len(moves)}, matched to a state message {len(delays)}")
    if delays:
        p95 = delays[int(0.95 * (len(delays) - 1))]
        print(
            f"MQTT state -> page DOM: median {statistics.median(delays) * 1000:.0f} ms, "
            f"p95 {p95 * 1000:.0f} ms, max {delays[-1] * 1000:.0f} ms"
        )
    if intervals:
        print(
            f"state message interval per vehicle: median {statistics.median(intervals):.2f} s, "
            f"max {max(intervals):.2f} s"
        )
    total = sum(cpu.values())
    print(
        f"page server (companion watch) CPU {cpu[watch]:.1f} s = {100 * cpu[watch] / window:.1f} % "
        f"of one core; the whole fleet {total:.1f} s = {100 * total / window:.0f} %"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
