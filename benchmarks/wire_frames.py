"""How fast the emulator and the companion build and read MAVLink 2 frames, in process (no
sockets): the per-frame cost of the wire code alone.

    .venv/bin/python benchmarks/wire_frames.py [--frames 20000] [--repeats 5]

Emulator: ``Encoder.frame`` of a ready payload (the fast streams' path), ``Encoder.pack`` of a
SYS_STATUS message object (the scalar fast path), the same signed, and ``FrameDecoder.feed`` of
datagrams of three SET_POSITION_TARGET_LOCAL_NED frames (what the companions send it).
Companion: the split and unpack of datagrams of LOCAL_POSITION_NED + NAMED_VALUE_FLOAT (what a
vehicle sends it every tick) and the setpoint's frame. Printed: microseconds per frame, the best
of ``--repeats`` (the least disturbed by the other processes of the machine).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from companion.link import fast_frames
from mavlink_wire import SigningState, passphrase_to_secret
from mavlink_wire import frames as wire
from sim_vehicle_stub.encoder import Encoder
from sim_vehicle_stub.framing import FrameDecoder, LinkStats


def _best(run: Callable[[], None], frames: int, repeats: int) -> float:
    """Microseconds per frame of ``run`` (which handles ``frames`` frames), best of ``repeats``."""
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - start)
    return best / frames * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=20000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    n, reps = args.frames, args.repeats

    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    setpoint = mav.set_position_target_local_ned_encode(
        1000, 1, 1, 1, 0b110111000011, 10.0, 20.0, -30.0, 1.0, 2.0, 0.0, 0, 0, 0, 0.5, 0
    )
    sp_payload = bytes(setpoint.pack(mav))[10:-2]
    status = mav.sys_status_encode(1, 1, 1, 100, 1, 500, 9, 0, 0, 0, 0, 0, 0)
    lpn = mav.local_position_ned_encode(1000, 10.0, 20.0, -30.0, 1.0, 2.0, 0.0)
    nvf = mav.named_value_float_encode(1000, b"SENS_SIG", 0.25)
    tick = bytes(lpn.pack(mav)) + bytes(nvf.pack(mav))
    sp_datagram = b"".join(bytes(setpoint.pack(mav)) for _ in range(3))
    lpn_id, sp_id = lpn.id, setpoint.id

    plain = Encoder(1)
    signed = Encoder(1, signing=SigningState(passphrase_to_secret("benchmark-key")))
    decoder = FrameDecoder(LinkStats())

    def emu_frame() -> None:
        for _ in range(n):
            plain.frame(sp_id, sp_payload)

    def emu_pack() -> None:
        for _ in range(n):
            plain.pack(status)

    def emu_pack_signed() -> None:
        for _ in range(n):
            signed.pack(status)

    def emu_decode() -> None:
        for _ in range(n // 3):
            decoder.feed(sp_datagram)

    def comp_read() -> None:
        for _ in range(n // 2):
            for msg_id, _, frame in wire.split(tick) or ():
                if msg_id == lpn_id:
                    fast_frames.unpack(msg_id, frame)

    def comp_frame() -> None:
        for k in range(n):
            fast_frames.frame(sp_id, sp_payload, k & 0xFF, 255, 190)

    rows = [
        ("emulator", "frame of a payload", emu_frame, n),
        ("emulator", "pack SYS_STATUS", emu_pack, n),
        ("emulator", "pack SYS_STATUS signed", emu_pack_signed, n),
        ("emulator", "decode setpoints", emu_decode, n // 3 * 3),
        ("companion", "split+unpack a tick", comp_read, n // 2 * 2),
        ("companion", "frame a setpoint", comp_frame, n),
    ]
    print(f"{'side':10} {'what':26} {'us/frame':>9}")
    for side, what, run, frames in rows:
        print(f"{side:10} {what:26} {_best(run, frames, reps):9.2f}")


if __name__ == "__main__":
    main()
