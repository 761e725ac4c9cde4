"""OPC UA figures: value change at the desk → seen by a subscribed client (median), and
the server's cost with 50 subscribed items at 10 Hz (CPU of its process, the desk's
cost of feeding it, the longest event-loop stall of the server).

    PYTHONPATH=. python bench/opcua_bench.py [--seconds 30] [--idle-seconds 10]
                                             [--vary some|all] [--none] [--probe]
                                             [--no-gc-freeze] [--no-browse-cache]
                                             [--no-fast-path] [--profile PREFIX]

The server runs in a process of its own (app/interop/opcua/child.py). Its CPU is that
process's CPU time (``time.process_time``, asked over its pipe at the start and the end
of a run), never wall clock; the machine may be shared, so the same figure is first
taken idle (the client subscribed, nothing changing) as a baseline. What the desk
spends feeding it is counted beside: its listeners' posts (on the desk's thread), the
thread that pickles and writes them to the pipe, and the drain of the server's
messages. ``--vary some`` changes what a robot's stream changes (gas, temperature,
humidity, battery, mode, x, meter values; the rest repeat their values), ``--vary all``
gives every one of the 50 items a new value every cycle.

Stalls are those of the server's own loop (in its process): a task sleeping 50 ms
notes how late it wakes. Each stall is told apart as the CPU the loop's thread used
in its window (``time.thread_time``: our code, or asyncua's, running long), the CPU of
the server process's other threads (its pipe's reader and writer), garbage collections
inside it, and the window time in which no thread of the process ran (a loaded
machine's scheduler gave the CPUs to other processes). ``--probe`` also times every
callback of the server's loop (wall and thread CPU, the longest named); it costs a
little CPU, so the CPU figure is taken without it. ``--profile PREFIX`` writes cProfiles of
the server's loop (idle and run), timed in the loop thread's CPU; ``--no-fast-path``
serves values as asyncua does (app/interop/opcua/fast_path.py not installed).

Client: asyncua's Client in this (the desk's) process (its own thread and loop),
loopback, user name and password, Basic256Sha256 SignAndEncrypt unless --none.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import statistics
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from asyncua import Client, ua
from asyncua.crypto.cert_gen import setup_self_signed_certificate
from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256
from cryptography.x509.oid import ExtendedKeyUsageOID
from opcua_loop_report import (  # beside this script
    LoopWatch,
    add_arguments,
    server_options,
)

from app.comm import protocol as P
from app.config import OpcuaSettings
from app.core.desk.pipeline import DeskPipeline
from app.core.meter_service import MeterRecord
from app.interop.opcua.server import OpcUaDeskServer
from app.interop.opcua.space import NS_URI
from app.interop.opcua.users import UserStore

N_GAUGES = 8  # 13 telemetry + 2 mode + 3 pose + 8 × 4 meter = 50 items


def server_cpu_s(server: OpcUaDeskServer) -> float:
    """The CPU time of the server's process so far."""
    return server.stats()["cpu_s"]


def feed_cpu_s(server: OpcUaDeskServer) -> float:
    """The desk's CPU in feeding the server so far, but for its listeners' posts: the
    thread that writes to the pipe, and the drain of the server's messages."""
    st = server.stats()
    return st["feed_cpu_s"] + st["drain_cpu_s"]


@dataclass
class Seen:
    sent: dict
    got: dict


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--idle-seconds", type=float, default=10.0)
    ap.add_argument("--vary", choices=("some", "all"), default="some")
    ap.add_argument("--none", action="store_true", help="security None (no encryption)")
    ap.add_argument("--profile", metavar="PREFIX", default="",
                    help="cProfile the server's loop: PREFIX.idle.prof and PREFIX.run.prof")
    add_arguments(ap)
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp())
    users = UserStore(tmp / "users.json")
    users.add("scada", "viewer", "bench-password")
    pipe = DeskPipeline()
    settings = OpcuaSettings(endpoint="opc.tcp://127.0.0.1:0", allow_none_security=args.none,
                             trusted_dir=str(tmp / "trusted"))
    server = OpcUaDeskServer(settings, users=users, pki_dir=tmp / "pki",
                             **server_options(args))
    server.attach(pipe)
    server.start()
    key, cert = tmp / "ck.pem", tmp / "cc.der"
    asyncio.run(setup_self_signed_certificate(key, cert, "urn:bench:scada", "localhost",
                                              [ExtendedKeyUsageOID.CLIENT_AUTH],
                                              {"commonName": "bench"}))
    (tmp / "trusted").mkdir(exist_ok=True)
    (tmp / "trusted" / "scada.der").write_bytes(cert.read_bytes())
    pipe.ingest("link_state", "connected")
    seen = Seen({}, {})
    ready, done = threading.Event(), threading.Event()
    n_items = [0]

    class Handler:
        def datachange_notification(self, node, val, data):
            if node.nodeid.Identifier == "Environment.gas_lel_pct" and val in seen.sent:
                seen.got.setdefault(val, time.perf_counter())

    async def client_main() -> None:
        c = Client(server.url, timeout=10)
        c.application_uri = "urn:bench:scada"
        if not args.none:
            await c.set_security(SecurityPolicyBasic256Sha256, str(cert), str(key),
                                 mode=ua.MessageSecurityMode.SignAndEncrypt)
        c.set_user("scada")
        c.set_password("bench-password")
        async with c:
            idx = await c.get_namespace_index(NS_URI)
            keys = [k for k in server.stats()["items"] if k.startswith(("Environment.",
                                                                         "Robot.Pose."))]
            keys += ["Robot.BatteryPercent", "Robot.Mode", "Robot.ModeCode"]
            keys += [f"Meters.G{g}.{f}" for g in range(N_GAUGES)
                     for f in ("Value", "Confidence", "State", "Point")]
            sub = await c.create_subscription(100, Handler())
            await sub.subscribe_data_change([c.get_node(ua.NodeId(k, idx)) for k in keys])
            n_items[0] = len(keys)
            ready.set()
            while not done.is_set():
                await asyncio.sleep(0.1)

    every = args.vary == "all"

    def meters(i: int, t: float) -> None:
        for g in range(N_GAUGES):
            conf, state = (0.9 - 1e-4 * i, f"normal {i}") if every else (0.9, "normal")
            pipe._emit("meter_record", MeterRecord(
                f"G{g}", f"P{g}{i if every else ''}", 0.1 * i, "MPa", 0.0, 1.0, state, conf,
                None, "", t, 5, 5, "patrol"))

    # the gauges' nodes exist once a first reading came
    meters(0, time.time())
    time.sleep(0.5)
    th = threading.Thread(target=lambda: asyncio.run(client_main()), daemon=True)
    th.start()
    assert ready.wait(30), "client did not subscribe"
    time.sleep(1.0)
    if args.profile:
        server.query("profile")
    idle_cpu0, idle_wall0 = server_cpu_s(server), time.perf_counter()
    time.sleep(args.idle_seconds)
    idle_pct = (server_cpu_s(server) - idle_cpu0) / (time.perf_counter() - idle_wall0) * 100
    if args.profile:
        server.query("profile", path=str(Path(args.profile + ".idle.prof").resolve()))
        server.query("profile")
    st0 = server.stats()
    cpu0, proc0, feed0 = server_cpu_s(server), time.process_time(), feed_cpu_s(server)
    wall0, post_s, i = time.perf_counter(), 0.0, 0
    writes0 = server.stats()["writes"]
    load0 = os.getloadavg()[0]
    watch = LoopWatch(server, args.seconds, args.probe)
    next_t = wall0
    while time.perf_counter() - wall0 < args.seconds:
        i += 1
        t = time.time()
        gas = float(i)
        if every:
            m = P.Telemetry(i, *(k + i * 1e-3 for k in range(12)), mode=2 + i % 2)
            m.gas_lel_pct, m.battery_v = gas, 24 - i * 1e-4
        else:
            m = P.Telemetry(gas_lel_pct=gas, temp_c=20 + i % 7, humidity_pct=40 + i % 5,
                            battery_v=24 - i * 1e-4, mode=2 + i % 2)
        m.received_s = t
        seen.sent[gas] = time.perf_counter()
        pipe.ingest("telemetry", m)  # the desk's own work is not the server's cost:
        c1 = time.thread_time()      # only the posting done by the listeners is counted
        pipe._emit("pose", P.Pose(i * 0.01, 1.0 + i * every * 1e-3, 0.1 + i * every * 1e-4))
        meters(i, t)
        post_s += time.thread_time() - c1
        next_t += 0.1
        while True:  # the desk's 50 ms drain timer, until the next cycle
            server.drain()
            left = next_t - time.perf_counter()
            if left <= 0:
                break
            time.sleep(min(0.05, left))
    wall = time.perf_counter() - wall0
    cpu, proc = server_cpu_s(server) - cpu0, time.process_time() - proc0
    feed = feed_cpu_s(server) - feed0
    st1 = server.stats()
    writes = st1["writes"] - writes0
    loop_cpu, sys_cpu = (st1[k] - st0[k] for k in ("loop_cpu_s", "sys_cpu_s"))
    load1 = os.getloadavg()[0]
    report = watch.stop(wall)
    if args.profile:
        server.query("profile", path=str(Path(args.profile + ".run.prof").resolve()))
    time.sleep(1.0)
    done.set()
    th.join(10)
    lat = sorted((seen.got[v] - seen.sent[v]) * 1000 for v in seen.got)
    server.stop()
    print(f"items subscribed: {n_items[0]} at 10 Hz for {wall:.1f} s "
          f"({'None' if args.none else 'Basic256Sha256 SignAndEncrypt'}, publishing 100 ms)")
    print(f"value change -> client: median {statistics.median(lat):.0f} ms, "
          f"p95 {lat[int(0.95 * len(lat))]:.0f} ms, max {lat[-1]:.0f} ms, "
          f"{len(lat)}/{i} changes seen")
    print(f"server process CPU: {cpu / wall * 100:.1f} % of one core "
          f"(idle baseline, subscribed and nothing changing: {idle_pct:.1f} %)"
          f"{' (callback probe on)' if args.probe else ''}")
    print(f"  of which: the loop's thread {loop_cpu / wall * 100:.1f} %, the process's other "
          f"threads {(cpu - loop_cpu) / wall * 100:.1f} %; in the kernel (all threads) "
          f"{sys_cpu / wall * 100:.1f} %")
    print(f"desk feeding it: {(post_s + feed) / wall * 100:.2f} % of one core (posts "
          f"{post_s / wall * 100:.2f} %, pipe writer thread and drain "
          f"{feed / wall * 100:.2f} %); server + feeding "
          f"{(cpu + post_s + feed) / wall * 100:.1f} %")
    for line in report:
        print(line)
    print(f"machine load (1 min): {load0:.1f} at start, {load1:.1f} at end "
          f"({os.cpu_count()} CPUs)")
    print(f"values changing: {args.vary}; node writes {writes / wall:.0f}/s; the desk's "
          f"process (pipeline, feeding, client) {proc / wall * 100:.1f} % of one core")
    print(f"desk thread, posting to the server: {post_s / i * 1e6:.0f} us per 10 Hz cycle "
          f"(pose + {N_GAUGES} meter records; telemetry's post is inside ingest)")


if __name__ == "__main__":
    main()
