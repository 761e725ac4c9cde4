import socket

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
