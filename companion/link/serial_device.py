"""A serial device (a flight controller's TELEM port, a USB adapter, a pseudo-terminal) opened for
a MAVLink link: raw 8N1 at the URL's baud rate, no modem control, locked against a second user.

:func:`open_serial` raises :class:`~companion.errors.InputError` naming the device and why it
cannot be had (missing, busy, no permission, not a terminal), so that `companion run` refuses it
before the flight with exit status 2 (:func:`check_serial`)."""

from __future__ import annotations

import errno
import fcntl
import os
import termios

from companion.errors import InputError
from companion.link.address import Address


def _why(device: str, exc: OSError) -> str:
    if exc.errno == errno.ENOENT:
        return f"serial device {device}: does not exist (is the cable in, the adapter powered?)"
    if exc.errno in (errno.EACCES, errno.EPERM):
        return (
            f"serial device {device}: no permission to open it (add the user to its group, "
            "e.g. `sudo usermod -aG dialout $USER`, and log in again)"
        )
    if exc.errno in (errno.EBUSY, errno.EWOULDBLOCK):
        return f"serial device {device}: busy (another program holds it: a ground station, MAVProxy, a getty?)"
    return f"serial device {device}: {exc.strerror or exc}"


def open_serial(address: Address) -> int:
    """A non-blocking file descriptor of ``address``'s device, raw at its baud rate, locked
    (flock, and TIOCEXCL: no other program opens it while the link has it)."""
    device, baud = address.host, address.port
    try:
        fd = os.open(device, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    except OSError as exc:
        raise InputError(_why(device, exc)) from exc
    try:
        if not os.isatty(fd):
            raise InputError(f"serial device {device}: not a terminal device")
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        fcntl.ioctl(fd, termios.TIOCEXCL)
        speed = getattr(termios, f"B{baud}")
        attrs = termios.tcgetattr(fd)
        attrs[0] = 0  # iflag: no translation, no software flow control
        attrs[1] = 0  # oflag: raw out
        attrs[2] = termios.CS8 | termios.CREAD | termios.CLOCAL  # 8N1, ignore modem lines
        attrs[3] = 0  # lflag: no echo, no canonical mode, no signals
        attrs[4] = attrs[5] = speed
        attrs[6][termios.VMIN] = 0
        attrs[6][termios.VTIME] = 0
        termios.tcsetattr(fd, termios.TCSANOW, attrs)
        termios.tcflush(fd, termios.TCIOFLUSH)
    except OSError as exc:
        os.close(fd)
        raise InputError(_why(device, exc)) from exc
    except InputError:
        os.close(fd)
        raise
    return fd


def check_serial(address: Address) -> None:
    """Open and close the device once: raises InputError naming it where it cannot be had."""
    os.close(open_serial(address))


def baud_of(fd: int) -> int:
    """The baud rate the device is set to (its output speed)."""
    speed = termios.tcgetattr(fd)[5]
    for name in dir(termios):
        if name.startswith("B") and name[1:].isdigit() and getattr(termios, name) == speed:
            return int(name[1:])
    raise ValueError(f"unknown termios speed {speed}")
