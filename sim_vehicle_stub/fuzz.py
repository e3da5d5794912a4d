"""A seeded corpus of malformed MAVLink datagrams, every one of which a vehicle must reject."""

from __future__ import annotations

import numpy as np

from sim_vehicle_stub.mavlink import dialect as d

KINDS = ("truncated", "bad_crc", "payload_flip", "unknown_id", "garbage", "bad_length", "flags")


def _valid_frames(target: int) -> list[bytes]:
    mav = d.MAVLink(None, srcSystem=245, srcComponent=190)
    msgs = [
        d.MAVLink_command_long_message(target, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0),
        d.MAVLink_command_long_message(target, 1, 176, 0, 1, 6, 0, 0, 0, 0, 0),
        d.MAVLink_param_set_message(target, 1, b"MDM_SENSOR", 1.0, 6),
        d.MAVLink_set_position_target_local_ned_message(
            0, target, 1, 1, 3527, 0, 0, 0, 5, 5, 0, 0, 0, 0, 0, 0
        ),
        d.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3),
        d.MAVLink_param_request_list_message(target, 1),
    ]
    return [bytes(m.pack(mav)) for m in msgs]


def _crc_ok_unknown(rng: np.random.Generator) -> bytes:
    plen = int(rng.integers(1, 40))
    msgid = int(rng.integers(60000, 2**24))
    while msgid in d.mavlink_map:
        msgid += 1
    head = bytes([0xFD, plen, 0, 0, 0, 245, 190, msgid & 255, (msgid >> 8) & 255, msgid >> 16])
    return head + rng.integers(0, 256, plen, dtype=np.uint8).tobytes() + b"\x00\x00"


def malformed_corpus(n: int, seed: int, target: int) -> list[tuple[str, bytes]]:
    """``n`` (kind, datagram) pairs; each datagram holds no frame a parser may accept."""
    rng = np.random.default_rng(seed)
    frames = _valid_frames(target)
    out: list[tuple[str, bytes]] = []
    for _ in range(n):
        kind = KINDS[int(rng.integers(len(KINDS)))]
        base = bytearray(frames[int(rng.integers(len(frames)))])
        if kind == "truncated":
            data = bytes(base[: int(rng.integers(1, len(base) - 1))])
        elif kind == "bad_crc":
            base[-1 - int(rng.integers(2))] ^= int(rng.integers(1, 256))
            data = bytes(base)
        elif kind == "payload_flip":
            k = int(rng.integers(10, len(base) - 2))
            base[k] ^= 1 << int(rng.integers(8))
            data = bytes(base)
        elif kind == "unknown_id":
            data = _crc_ok_unknown(rng)
        elif kind == "garbage":
            junk = rng.integers(0, 256, int(rng.integers(1, 300)), dtype=np.uint8)
            junk[(junk == 0xFD) | (junk == 0xFE)] = 0x55
            data = junk.tobytes()
        elif kind == "bad_length":
            base[1] = min(255, base[1] + int(rng.integers(1, 100)))
            data = bytes(base)
        else:  # unknown incompatibility flags
            base[2] |= 1 << int(rng.integers(1, 8))
            data = bytes(base)
        out.append((kind, data))
    return out
