"""OPC UA alarm figures: an alarm raised on the desk → its condition event at a
subscribed client; the client's Acknowledge → acknowledged on the desk (the desk's
thread runs the call from its 50 ms timer, as the window and the headless desk do).

    PYTHONPATH=. python bench/opcua_alarm_bench.py [--rounds 20] [--probe] [--profile OUT]
                                                   [--no-gc-freeze] [--no-browse-cache]

The server loop's stalls during the rounds are told apart as in opcua_bench.py
(``--probe``: every callback of its loop timed, wall and thread CPU).

The server runs in a process of its own; the client is asyncua's Client in this (the
desk's) process (own thread and loop), loopback, user name and password,
Basic256Sha256 SignAndEncrypt.
"""

from __future__ import annotations

import argparse
import asyncio
import statistics
import tempfile
import threading
import time
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
from app.interop.opcua.server import OpcUaDeskServer
from app.interop.opcua.space import NS_URI
from app.interop.opcua.users import UserStore

KEY = "gas_lel_pct.high"
ACK = ua.NodeId(ua.ObjectIds.AcknowledgeableConditionType_Acknowledge)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=20)
    add_arguments(ap)
    ap.add_argument("--profile", metavar="OUT",
                    help="cProfile the server's thread during the rounds into OUT")
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp())
    users = UserStore(tmp / "users.json")
    users.add("scada", "operator", "bench-password")
    pipe = DeskPipeline()
    server = OpcUaDeskServer(OpcuaSettings(endpoint="opc.tcp://127.0.0.1:0",
                                           trusted_dir=str(tmp / "trusted")),
                             users=users, pki_dir=tmp / "pki",
                             **server_options(args))
    server.attach(pipe)
    server.start()
    key, cert = tmp / "ck.pem", tmp / "cc.der"
    asyncio.run(setup_self_signed_certificate(key, cert, "urn:bench:scada", "localhost",
                                              [ExtendedKeyUsageOID.CLIENT_AUTH],
                                              {"commonName": "bench"}))
    (tmp / "trusted").mkdir(exist_ok=True)
    (tmp / "trusted" / "scada.der").write_bytes(cert.read_bytes())
    raised_at: dict[int, float] = {}
    seen_at: dict[int, float] = {}
    ack_called: dict[int, float] = {}
    ready, done = threading.Event(), threading.Event()
    rnd = [0]

    async def client_main() -> None:
        c = Client(server.url, timeout=10)
        c.application_uri = "urn:bench:scada"
        await c.set_security(SecurityPolicyBasic256Sha256, str(cert), str(key),
                             mode=ua.MessageSecurityMode.SignAndEncrypt)
        c.set_user("scada")
        c.set_password("bench-password")
        q: asyncio.Queue = asyncio.Queue()

        class H:
            def event_notification(self, ev):
                if ev.ConditionName == KEY and ev.AckedState.Text == "Unacknowledged" \
                        and ev.ActiveState.Text == "Active":
                    seen_at.setdefault(rnd[0], time.perf_counter())
                    q.put_nowait((rnd[0], ev.EventId))

        async with c:
            idx = await c.get_namespace_index(NS_URI)
            sub = await c.create_subscription(50, H())
            await sub.subscribe_events(c.nodes.server, ua.ObjectIds.LimitAlarmType)
            ready.set()
            while not done.is_set():
                try:
                    r, eid = await asyncio.wait_for(q.get(), 0.2)
                except TimeoutError:
                    continue
                ack_called[r] = time.perf_counter()
                await c.get_node(ua.NodeId(f"Alarms.{KEY}", idx)).call_method(
                    ACK, ua.Variant(eid, ua.VariantType.ByteString), ua.LocalizedText("bench"))

    th = threading.Thread(target=lambda: asyncio.run(client_main()), daemon=True)
    th.start()
    assert ready.wait(30)
    pipe.ingest("link_state", "connected")
    t = time.time()
    acked_lat = []

    def feed(gas: float) -> None:
        nonlocal t
        t += 3.0  # telemetry time: past the gas alarm's 2 s off-delay each step
        m = P.Telemetry(gas_lel_pct=gas, battery_v=24.0)
        m.received_s = t
        pipe.ingest("telemetry", m)

    feed(1.0)
    if args.profile:
        server.query("profile")
    wall0 = time.perf_counter()
    # the control loops are watched for about as long as the rounds take
    watch = LoopWatch(server, 1.2 * args.rounds, args.probe)
    for r in range(1, args.rounds + 1):
        rnd[0] = r
        raised_at[r] = time.perf_counter()
        feed(15.0)
        end = time.perf_counter() + 5.0
        while time.perf_counter() < end:  # the desk's thread: its 50 ms timer
            server.drain()
            a = pipe.monitor.get(KEY)
            if a is not None and a.acked_by == "opcua:scada" and a.acknowledged and r in \
                    ack_called:
                acked_lat.append((time.perf_counter() - ack_called[r]) * 1000)
                break
            time.sleep(0.05)
        feed(1.0)
        feed(1.0)
    wall = time.perf_counter() - wall0
    if args.profile:
        server.query("profile", path=str(Path(args.profile).resolve()))
    report = watch.stop(wall)
    done.set()
    th.join(10)
    server.stop()
    ev_lat = sorted((seen_at[r] - raised_at[r]) * 1000 for r in seen_at)
    print(f"alarm raised -> condition event at the client: median "
          f"{statistics.median(ev_lat):.0f} ms, max {ev_lat[-1]:.0f} ms "
          f"({len(ev_lat)}/{args.rounds}; subscription publishing 50 ms)")
    print(f"client Acknowledge -> acknowledged on the desk: median "
          f"{statistics.median(acked_lat):.0f} ms, max {max(acked_lat):.0f} ms "
          f"({len(acked_lat)}/{args.rounds}; desk timer 50 ms)")
    for line in report:
        print(line)


if __name__ == "__main__":
    main()
