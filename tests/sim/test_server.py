import socket

from waits import wait_until

from app.comm import protocol as P
from sim_robot.server import Client, TcpServer


def _server(**kw):
    return TcpServer("127.0.0.1", 0, lambda c, f: None, **kw)


def test_slow_client_drops_video_first_never_telemetry():
    srv = _server(queue_bytes=10_000, max_backlog_bytes=1_000_000)
    a, b = socket.socketpair()
    try:
        c = Client(srv, a, ("test", 0), 1)  # no writer thread: nothing leaves the queue
        jpeg = b"\xff\xd8" + bytes(3000)
        for i in range(20):
            c.send(P.VideoFrame(i, 0, 640, 480, 0.0, jpeg), is_video=True)
            c.send(P.Telemetry(mcu_time_ms=i))
            c.send(P.Event("info", "x", str(i)))
        kinds = [v for v, _ in c._q]
        assert kinds.count(False) == 40  # every telemetry and event kept
        assert c.video_dropped >= 15
        assert c.queued_bytes() <= 10_000 + 3100
    finally:
        srv.close()
        a.close()
        b.close()


def test_client_that_never_reads_is_cut_off():
    srv = _server(queue_bytes=1_000, max_backlog_bytes=5_000)
    a, b = socket.socketpair()
    try:
        c = Client(srv, a, ("test", 0), 1)
        for i in range(200):
            c.send(P.Telemetry(mcu_time_ms=i))
        assert c.closed
    finally:
        srv.close()
        b.close()


def test_connections_beyond_the_per_peer_limit_are_closed_and_reported():
    refused = []
    srv = _server(max_clients=16, max_per_host=3,
                  on_reject=lambda addr, why: refused.append(why))
    srv.start()
    socks = []
    try:
        for _ in range(6):
            socks.append(socket.create_connection(srv.address, timeout=2))
        wait_until(lambda: len(refused) >= 3 and len(srv.clients) >= 3, 5)
        assert len(srv.clients) == 3 and srv.rejected_connections == 3
        assert all("limit 3" in why for why in refused)
        # a refused socket is closed by the server: reading gives EOF (or a reset)
        closed = 0
        for s in socks[3:]:
            s.settimeout(2)
            try:
                closed += s.recv(1) == b""
            except ConnectionResetError:
                closed += 1
        assert closed == 3
    finally:
        for s in socks:
            s.close()
        srv.close()


def test_command_rate_is_limited_per_client():
    srv = _server()
    a, b = socket.socketpair()
    try:
        c = Client(srv, a, ("test", 0), 1)
        t = c.connected_at
        assert sum(c.take_token(10.0, t) for _ in range(15)) == 10  # a burst of 10
        assert not c.take_token(10.0, t + 0.05)
        assert c.take_token(10.0, t + 0.15)  # refilled at 10 per second
    finally:
        srv.close()
        a.close()
        b.close()
