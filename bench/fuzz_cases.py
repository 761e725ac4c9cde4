"""Seeded hostile-input generator for the two frame decoders (no Qt).

Used by ``bench/fuzz.py`` (>= 100 000 inputs) and by
``tests/security/test_fuzz.py`` (fewer). It lives with the benchmarks, not in
app/comm: it drives both sides' decoders (the desk's codec and the robot's MCU
link), and the desk's code never needs it.
Each case builds a byte stream from valid frames and damages it — random
bytes, bit flips, truncation, a rewritten length with its header checksum
fixed (a well-formed header that lies), oversize lengths, spliced and
repeated frames, payloads cut or stretched and re-framed with correct
checksums (so the message decoders see them), floods of magic bytes — feeds
it in random chunks, then feeds a known-good sentinel frame and checks that
it comes out. Any exception escaping ``feed`` is recorded.
"""

from __future__ import annotations

import binascii
import random
import struct
import traceback
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from app.comm import protocol as P
from sim_robot import mcu_link as M

MUTATIONS = ("random", "bitflip", "truncate", "lying_length", "oversize_length", "splice",
             "payload_resize", "payload_garbage", "magic_flood", "header_only", "json_junk")


@dataclass
class FuzzResult:
    cases: int = 0
    raised: int = 0
    sentinel_lost: int = 0
    frames_decoded: int = 0
    by_mutation: Counter = field(default_factory=Counter)
    drops: Counter = field(default_factory=Counter)
    first_errors: list[str] = field(default_factory=list)

    def as_dict(self) -> dict:
        return {"cases": self.cases, "raised": self.raised,
                "sentinel_lost": self.sentinel_lost, "frames_decoded": self.frames_decoded,
                "by_mutation": dict(self.by_mutation), "drops_by_reason": dict(self.drops)}


def _link_samples(rng: random.Random) -> list:
    jpeg = b"\xff\xd8" + rng.randbytes(40)
    return [
        P.Heartbeat(0, 123, 4, 5),
        P.Telemetry(1000, 3.2, 21.0, 50.0, 1, 2, 3, 24.0, 0.1, 0.1, 0.0, 0.2, 0.0, 1, 2, 77),
        P.VideoFrame(1, 2, 640, 480, 0.1, jpeg),
        P.LidarScan(5, -3.1, 0.1, 12.0, np.arange(8, dtype=np.float32)),
        P.Pose(1.0, 2.0, 0.5, 0.1, 0.0),
        P.Event("warning", "x", "text", {"a": 1}),
        P.Command("drive", {"linear_mps": 0.3, "angular_rps": 0.0}),
        P.Command("stop", {}, {"desk": "d", "session": "s", "ctr": 1}, b"\x01" * 32),
        P.CommandAck(7, False, "no"),
        P.MapImage(0.1, 0.0, 0.0, 4, 4, b"\x89PNG" + rng.randbytes(20)),
        P.Path(0, np.zeros((3, 2), np.float32)),
        P.PatrolStatus("driving", "r", 1, [], "", 0.5, "dwa"),
        P.Obstacles(np.ones((2, 5), np.float32)),
    ]


def _relength(frame: bytes, new_len: int) -> bytes:
    """Rewrite a frame's length field and fix its header checksum."""
    head = bytearray(frame[:P.HEADER_SIZE])
    struct.pack_into("<I", head, 4, new_len & 0xFFFFFFFF)
    struct.pack_into("<H", head, 20, binascii.crc_hqx(bytes(head[2:20]), 0xFFFF))
    return bytes(head) + frame[P.HEADER_SIZE:]


def _common_mutation(kind: str, rng: random.Random, frames: list[bytes], *,
                     max_random: int, max_flips: int) -> bytes | None:
    """The mutations both decoders get: random bytes, bit flips, a truncated
    frame, and one frame's head spliced onto another's tail (then the first
    frame whole). None for a kind that is not one of these."""
    f = frames[0]
    if kind == "random":
        return rng.randbytes(rng.randint(0, max_random))
    if kind == "bitflip":
        b = bytearray(b"".join(frames))
        for _ in range(rng.randint(1, max_flips)):
            i = rng.randrange(len(b))
            b[i] ^= 1 << rng.randrange(8)
        return bytes(b)
    if kind == "truncate":
        return f[:rng.randrange(len(f))]
    if kind == "splice":
        b = frames[-1]
        return f[:rng.randrange(len(f))] + b[rng.randrange(len(b)):] + f
    return None


def link_case(rng: random.Random, samples: list, enc: P.FrameEncoder) -> tuple[str, bytes]:
    kind = rng.choice(MUTATIONS)
    frames = [enc.encode(rng.choice(samples)) for _ in range(rng.randint(1, 3))]
    f = frames[0]
    data = _common_mutation(kind, rng, frames, max_random=400, max_flips=8)
    if data is not None:
        pass  # one of the mutations both decoders get
    elif kind == "lying_length":
        n = len(f) - P.HEADER_SIZE - P.TRAILER_SIZE
        data = _relength(f, max(0, n + rng.randint(-n, 64)))
    elif kind == "oversize_length":
        data = _relength(f, rng.randint(P.MAX_PAYLOAD + 1, 0xFFFFFFFF))
    elif kind == "payload_resize":
        msg = rng.choice(samples)
        p = msg.pack()
        p = p[:rng.randrange(len(p) + 1)] if rng.random() < 0.5 else p + rng.randbytes(
            rng.randint(1, 16))
        data = enc.encode_raw(int(msg.TYPE), p)
    elif kind == "payload_garbage":
        t = rng.choice(list(P.MsgType)) if rng.random() < 0.9 else rng.randint(0, 255)
        data = enc.encode_raw(int(t), rng.randbytes(rng.randint(0, 200)))
    elif kind == "magic_flood":
        data = (P.MAGIC * rng.randint(1, 200)) + f[:rng.randrange(len(f))]
    elif kind == "header_only":
        data = f[:P.HEADER_SIZE] * rng.randint(1, 5)
    else:  # json_junk: JSON messages whose fields have the wrong types or shapes
        t = rng.choice((P.MsgType.EVENT, P.MsgType.COMMAND, P.MsgType.PATROL_STATUS))
        junk = rng.choice((b"[]", b"{}", b'{"name":5,"args":[]}', b'{"args":{"a":1e999}}',
                           b'{"name":"x","auth":"y"}', b'{"points":7,"state":{}}', b"null",
                           b'{"name":"drive","args":{}}\x00' + rng.randbytes(32),
                           b'\x00' * 33, b'{"level":[1],"data":3}', rng.randbytes(50)))
        data = enc.encode_raw(int(t), junk)
    # garbage on either side, sometimes
    if rng.random() < 0.3:
        data = rng.randbytes(rng.randint(1, 30)) + data
    return kind, data


def _feed_chunks(dec, data: bytes, rng: random.Random) -> list:
    out = []
    i = 0
    while i < len(data):
        n = rng.choice((1, 2, 7, 64, 4096))
        out += dec.feed(data[i:i + n])
        i += n
    return out


def fuzz_link(n: int, seed: int = 0) -> FuzzResult:
    rng = random.Random(seed)
    samples = _link_samples(rng)
    enc = P.FrameEncoder()
    sentinel_msg = P.Event("info", "sentinel", "after garbage", {})
    res = FuzzResult()
    for _ in range(n):
        kind, data = link_case(rng, samples, enc)
        res.cases += 1
        res.by_mutation[kind] += 1
        dec = P.FrameDecoder()
        try:
            got = _feed_chunks(dec, data, rng)
            sentinel = enc.encode(sentinel_msg)
            got += dec.feed(sentinel)
            if not any(fr.msg_type == P.MsgType.EVENT and fr.message.code == "sentinel"
                       for fr in got):
                # a lying header may hold the sentinel as its body: the stream goes on
                got += dec.feed(b"\x00" * max(0, dec.pending_bytes) + sentinel)
            res.frames_decoded += len(got)
            if not any(fr.msg_type == P.MsgType.EVENT and fr.message.code == "sentinel"
                       for fr in got):
                res.sentinel_lost += 1
        except Exception:  # noqa: BLE001 - this is what the fuzzer looks for
            res.raised += 1
            if len(res.first_errors) < 5:
                res.first_errors.append(f"{kind}: {traceback.format_exc(limit=3)}")
        for k, v in dec.stats.as_dict().items():
            if k not in ("frames", "bytes_in", "dropped") and v:
                res.drops[k] += v
    return res


def fuzz_mcu(n: int, seed: int = 0) -> FuzzResult:
    rng = random.Random(seed)
    samples = [M.SensorReport(1, 2.0, 3.0, 4.0, 1, 1, 1, 24, 0.1, 0.1, 0.0, 5, 6, 0.1, 0.0,
                              3, 1, 0.5), M.MotorCmd(0.3, 0.1), M.Keepalive(),
               M.ConfigLimits(), M.Estop(True), M.Ack(0x10, 3, 0)]
    enc = M.McuEncoder()
    res = FuzzResult()
    kinds = ("random", "bitflip", "truncate", "wrong_length", "splice", "sync_flood",
             "payload_garbage")
    for _ in range(n):
        kind = rng.choice(kinds)
        frames = [enc.encode(rng.choice(samples)) for _ in range(rng.randint(1, 3))]
        f = frames[0]
        data = _common_mutation(kind, rng, frames, max_random=300, max_flips=6)
        if data is not None:
            pass  # one of the mutations both decoders get
        elif kind == "wrong_length":
            t = rng.choice(list(M.McuType))
            ln = rng.randint(0, 255)
            body = bytes((t, rng.randrange(256), ln)) + rng.randbytes(ln)
            data = M.SYNC + body + struct.pack("<H", M.crc16(body))
        elif kind == "sync_flood":
            data = M.SYNC * rng.randint(1, 100) + f[:rng.randrange(len(f))]
        else:
            t = rng.randint(0, 255)
            ln = M.PAYLOAD_LEN.get(t, rng.randint(0, 20))
            data = M.encode_frame(t, rng.randrange(256), rng.randbytes(ln))
        if rng.random() < 0.3:
            data = rng.randbytes(rng.randint(1, 30)) + data
        res.cases += 1
        res.by_mutation[kind] += 1
        dec = M.McuDecoder()
        try:
            got = _feed_chunks(dec, data, rng)
            sentinel = enc.encode(M.Estop(False))
            got += dec.feed(sentinel)
            if not any(fr.msg_type == M.McuType.ESTOP and fr.message.engage is False
                       for fr in got):
                # a cut frame's header may hold the sentinel: the line goes on
                got += dec.feed(b"\x00" * (M.MAX_LEN + M.OVERHEAD) + sentinel)
            res.frames_decoded += len(got)
            if not any(fr.msg_type == M.McuType.ESTOP and fr.message.engage is False
                       for fr in got):
                res.sentinel_lost += 1
        except Exception:  # noqa: BLE001
            res.raised += 1
            if len(res.first_errors) < 5:
                res.first_errors.append(f"{kind}: {traceback.format_exc(limit=3)}")
        for k, v in dec.stats.as_dict().items():
            if k not in ("frames", "bytes_in", "dropped") and v:
                res.drops[k] += v
    return res
