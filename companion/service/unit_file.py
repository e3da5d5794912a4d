"""The systemd unit `companion service` writes: one vehicle's `companion run`, started at boot.

Why each setting is there is said in the unit's own comments (they are part of the text written):
the restart policy, the stop that lets the vehicle land, the journal and the run directory's
bounded log file. Pure: the text from a :class:`UnitSpec`, no file written here.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

STATE_ROOT = Path("/var/lib/mdm-search")
"""Where the units' run directories go by default (systemd's StateDirectory=mdm-search)."""
_PLAIN = re.compile(r"[A-Za-z0-9_@%+=:,./-]+")


@dataclass(frozen=True)
class UnitSpec:
    """What one vehicle's unit runs and as whom."""

    companion: Path
    """The `companion` executable of the environment it was installed into (absolute)."""
    run_argv: tuple[str, ...]
    """`companion run`'s options, as given (profile, vehicle, link, system id, MQTT ...)."""
    log_dir: Path
    """The run directory: mission log, .tlog, companion.log; kept across restarts."""
    description: str
    """One line: which vehicle of which profile over which link."""
    user: str
    """The account it runs as (in the dialout group for a serial device)."""
    stop_timeout: float
    """Wall seconds systemd waits after SIGTERM before SIGKILL: the end action's landing."""
    serial_device: Path | None = None
    """The link's serial device, where it is one: the unit waits for it at boot."""


def device_unit(device: Path) -> str:
    """systemd's device unit of ``device`` (``systemd-escape --path --suffix device``)."""
    escaped = []
    for i, ch in enumerate(str(device).strip("/")):
        if ch == "/":
            escaped.append("-")
        elif ch.isascii() and (ch.isalnum() or ch in ":_" or (ch == "." and i > 0)):
            escaped.append(ch)
        else:
            escaped.append("".join(f"\\x{b:02x}" for b in ch.encode()))
    return "".join(escaped) + ".device"


def exec_quote(arg: str) -> str:
    """``arg`` as one word of a systemd command line (specifiers and variables escaped)."""
    arg = arg.replace("%", "%%").replace("$", "$$")
    if _PLAIN.fullmatch(arg):
        return arg
    return '"' + arg.replace("\\", "\\\\").replace('"', '\\"') + '"'


def render(spec: UnitSpec) -> str:
    """The unit file's text."""
    argv = [
        str(spec.companion), "run", *spec.run_argv,
        "--log-dir", str(spec.log_dir), "--log-file", str(spec.log_dir / "companion.log"),
        "--new-mission-per-boot", "--no-map",
    ]  # fmt: skip
    lines: list[list[str]] = []
    for arg in argv:  # one line per option and its value
        if arg.startswith("--") or not lines:
            lines.append([])
        lines[-1].append(exec_quote(arg))
    exec_start = " \\\n    ".join(" ".join(line) for line in lines)
    state = ""
    if spec.log_dir.is_relative_to(STATE_ROOT):  # systemd makes it, owned by the user
        state = f"StateDirectory={spec.log_dir.relative_to(STATE_ROOT.parent)}\n"
    device = ""
    if spec.serial_device is not None:
        unit = device_unit(spec.serial_device)
        device = (
            "# The serial device may appear late at boot (a USB adapter): wait for it (a cable\n"
            "# pulled later is a lost link the companion rides out, not a stop).\n"
            f"Wants={unit}\nAfter={unit}\n"
        )
    return f"""\
# Written by `companion service`; docs/companion.md, "On the vehicle".
[Unit]
Description={spec.description.replace("%", "%%")}
After=network-online.target
Wants=network-online.target
{device}# At most 3 starts in 10 minutes: a companion that cannot run is left failed, not looped.
StartLimitIntervalSec=600
StartLimitBurst=3

[Service]
Type=exec
User={spec.user}
SupplementaryGroups=dialout
{state}# --new-mission-per-boot: a restart reads the run directory's mission log and follows its
# resume rules (a vehicle in flight is never taken back as a new mission; an ended mission
# stays ended); only a mission that ended in an earlier boot is moved aside for a new one.
ExecStart={exec_start}
# Restart after a crash (an exit other than 0, a signal); never after bad input (exit 2:
# a restart would not mend it) or an operator's second Ctrl-C (130).
Restart=on-failure
RestartSec=5
RestartPreventExitStatus=2 130
# `systemctl stop`: SIGTERM to the companion, which flies the end action and waits for the
# landing; SIGKILL (to it and anything it started: KillMode=mixed) only after TimeoutStopSec.
KillMode=mixed
KillSignal=SIGTERM
TimeoutStopSec={spec.stop_timeout:.0f}
# The journal has every line (bounded by journald's SystemMaxUse); the run directory's
# companion.log is rotated at 5 MB, 3 kept; a full disk is one error line, never a crash.
StandardOutput=journal
StandardError=journal
SyslogIdentifier=mdm-companion
Environment=PYTHONUNBUFFERED=1
# The flight software is the last process the kernel's OOM killer should pick.
OOMScoreAdjust=-500
NoNewPrivileges=yes

[Install]
WantedBy=multi-user.target
"""
