"""Live Foxglove view benchmark: latency desk -> WebSocket client, and the desk's cost.

The desk pipeline is fed telemetry (all channels) at ``--hz`` with ``received_s`` = the
wall clock at ingest, a pose every 10th message and a 360-ray lidar scan every 5th; a
``websockets`` client (tests/interop/fgclient.py), subscribed to /telemetry, /pose,
/tf and /scan, stamps each message data frame on receipt. Latency = receipt time -
the message's log time (the ingest time), both on this machine's clock. Goal: median
<= 50 ms. Also the desk thread's CPU per ingest (``time.thread_time``) with the server
on and off.

    .venv/bin/python bench/foxglove_bench.py [--seconds 10] [--hz 50]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import numpy as np  # noqa: E402
from interop.fgclient import Client  # noqa: E402

from app.comm import protocol as P  # noqa: E402
from app.core.desk import DeskPipeline  # noqa: E402
from app.core.interop.foxglove_live import FoxgloveLive  # noqa: E402

TOPICS = ["/telemetry", "/pose", "/tf", "/scan"]


def drive(pipeline: DeskPipeline, seconds: float, hz: float) -> tuple[int, float]:
    """Feed for ``seconds``; (messages ingested, desk-thread CPU s spent in ingest)."""
    ranges = np.linspace(0.5, 8.0, 360).astype(np.float32)
    n, cpu = 0, 0.0
    start = time.perf_counter()
    i = 0
    while time.perf_counter() - start < seconds:
        due = start + i / hz
        if due > time.perf_counter():
            time.sleep(due - time.perf_counter())
        c0 = time.thread_time()
        msg = P.Telemetry(gas_lel_pct=2.0, temp_c=20.0 + (i % 10), humidity_pct=45.0,
                          battery_v=24.6, obstacle_front_m=3.0, mode=int(P.RobotMode.PATROL),
                          tel_seq=i)
        msg.received_s = time.time()
        pipeline.ingest("telemetry", msg)
        n += 1
        if i % 10 == 0:
            pipeline.ingest("pose", P.Pose(0.01 * i, 1.0, 0.1))
            n += 1
        if i % 5 == 0:
            pipeline.ingest("scan", P.LidarScan(0, -3.14159, 2 * 3.14159 / 360, 10.0, ranges))
            n += 1
        cpu += time.thread_time() - c0
        i += 1
    return n, cpu


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--hz", type=float, default=50.0)
    args = ap.parse_args(argv)

    base = DeskPipeline()
    n_off, cpu_off = drive(base, min(args.seconds, 5.0), args.hz)
    base.close()

    pipeline = DeskPipeline()
    live = FoxgloveLive(pipeline, port=0)
    client = Client(live.port, TOPICS)
    t_end = time.monotonic() + 5
    while client.subscribed() != set(TOPICS) and time.monotonic() < t_end:
        time.sleep(0.01)
    time.sleep(0.2)  # let the subscriptions reach the server
    first = len(client.messages)
    n_on, cpu_on = drive(pipeline, args.seconds, args.hz)
    time.sleep(0.5)
    got = client.messages[first:]
    client.close()
    live.close()
    pipeline.close()
    lat = {t: [(rx - ns / 1e9) * 1000 for top, ns, rx, _ in got if top == t] for t in TOPICS}
    every = sorted(x for v in lat.values() for x in v)
    print(f"foxglove live: {n_on} messages ingested over {args.seconds:g} s "
          f"({args.hz:g} Hz telemetry + poses + 360-ray scans); {live.sent} logged (a pose "
          f"is /pose and /tf), {len(got)} received by the client")
    for t, v in lat.items():
        if v:
            print(f"  {t:<11} {len(v):>5} received; latency median {statistics.median(v):.1f} ms,"
                  f" p95 {np.percentile(v, 95):.1f} ms, max {max(v):.1f} ms")
    if every:
        print(f"  all topics: median {statistics.median(every):.1f} ms (goal <= 50 ms), "
              f"p95 {np.percentile(every, 95):.1f} ms")
    print(f"  desk thread CPU per ingest: {cpu_on / n_on * 1e6:.0f} us with the server, "
          f"{cpu_off / n_off * 1e6:.0f} us without")
    return 0


if __name__ == "__main__":
    sys.exit(main())
