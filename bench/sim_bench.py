"""Figures for the simulated robot: camera ms/frame, lidar ms/scan, MCU ms/step,
and message rates and heartbeat round trip seen by a plain-socket desk.

    python bench/sim_bench.py [--seconds 10]
"""

from __future__ import annotations

import argparse
import collections
import math
import socket
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from app.comm import protocol as P  # noqa: E402
from sim_robot.camera import Camera  # noqa: E402
from sim_robot.config import RobotParams  # noqa: E402
from sim_robot.lidar import Lidar  # noqa: E402
from sim_robot.mcu import McuModel  # noqa: E402
from sim_robot.world import World  # noqa: E402


def timed(fn, n):
    out = []
    for _ in range(n):
        t = time.perf_counter()
        fn()
        out.append((time.perf_counter() - t) * 1000)
    return statistics.median(out), float(np.percentile(out, 95)), max(out)


def components() -> None:
    w = World(seed=0)
    cam = Camera(w)
    poses = [(66, 45, math.pi), (55.5, 35, math.pi), (30, 26, math.pi / 2), (60, 12, 0.7)]
    i = iter(range(10**9))

    def shot():
        p = poses[next(i) % len(poses)]
        cam.capture_jpeg(*p, 100.0)

    med, p95, mx = timed(shot, 200)
    print(f"camera render+JPEG 640x480: median {med:.1f} ms, p95 {p95:.1f} ms, max {mx:.1f} ms")
    lid = Lidar(w, np.random.default_rng(0))
    med, p95, mx = timed(lambda: lid.scan(66, 45, 0.3), 100)
    print(f"lidar 360 beams 12 m: median {med:.2f} ms, p95 {p95:.2f} ms")
    m = McuModel(w, RobotParams(), link_clock=lambda: 0.0)
    m.last_rx = 0.0
    k = iter(range(10**9))
    med, p95, mx = timed(lambda: m.step(next(k) * 0.05, 0.05), 400)
    print(f"MCU model step: median {med:.3f} ms, p95 {p95:.3f} ms")


def rates(seconds: float, time_scale: float) -> None:
    proc = subprocess.Popen([sys.executable, "-m", "sim_robot", "--seed", "1",
                             "--time-scale", str(time_scale)], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        host, port = proc.stdout.readline().split()[-1].rsplit(":", 1)
        s = socket.create_connection((host, int(port)))
        s.settimeout(0.05)
        dec, enc = P.FrameDecoder(), P.FrameEncoder()
        cnt: collections.Counter = collections.Counter()
        rtts, lat = [], []
        nbytes = 0
        t0 = last_hb = time.monotonic()
        while time.monotonic() - t0 < seconds:
            if time.monotonic() - last_hb > 1.0:
                last_hb = time.monotonic()
                s.sendall(enc.encode(P.Heartbeat(0)))
            try:
                data = s.recv(1 << 16)
            except TimeoutError:
                continue
            nbytes += len(data)
            for f in dec.feed(data):
                cnt[f.msg_type.name] += 1
                m = f.message
                if f.msg_type == P.MsgType.HEARTBEAT and m.echo_ts_us:
                    rtts.append((P.now_us() - m.echo_ts_us - m.echo_hold_us) / 1000)
                if f.msg_type == P.MsgType.VIDEO_FRAME:
                    lat.append((P.now_us() - m.capture_ts_us) / 1000)
        el = time.monotonic() - t0
        print(f"time scale {time_scale}: over {el:.1f} s, {nbytes / el / 1e3:.0f} kB/s")
        for k, v in sorted(cnt.items()):
            print(f"  {k:12s} {v / el:6.1f} /s")
        if rtts:
            print(f"  heartbeat RTT median {statistics.median(rtts):.1f} ms")
        if lat:
            print(f"  video capture->received median {statistics.median(lat):.1f} ms")
        print(f"  decoder dropped {dec.stats.dropped}")
        s.close()
    finally:
        proc.terminate()
        proc.wait(10)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=10.0)
    a = ap.parse_args()
    components()
    rates(a.seconds, 1.0)
    rates(a.seconds / 2, 20.0)


if __name__ == "__main__":
    main()
