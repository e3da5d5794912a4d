"""Drains the UDP ports the emulated vehicles send to and counts datagrams per port.

Run by the emulator benchmarks as a subprocess: ``emulator_sink.py BASE N``; prints a JSON list
of counts when it gets SIGTERM.
"""

from __future__ import annotations

import json
import selectors
import signal
import socket
import sys


def main() -> None:
    base, n = int(sys.argv[1]), int(sys.argv[2])
    sel = selectors.DefaultSelector()
    counts = [0] * n
    for i in range(n):
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
        sock.bind(("127.0.0.1", base + i))
        sock.setblocking(False)
        sel.register(sock, selectors.EVENT_READ, i)
    running = True

    def stop(*_: object) -> None:
        nonlocal running
        running = False

    signal.signal(signal.SIGTERM, stop)
    print("ready", flush=True)
    while running:
        for key, _ in sel.select(0.2):
            ready = key.fileobj
            if not isinstance(ready, socket.socket):
                continue
            while True:
                try:
                    ready.recv(65536)
                except BlockingIOError:
                    break
                counts[key.data] += 1
    print(json.dumps(counts), flush=True)


if __name__ == "__main__":
    main()
