from app.comm import protocol as P

from .conftest import wait_until


def test_heartbeat_echoes_the_desks_last_heartbeat(robot, desk_factory):
    desk = desk_factory(heartbeat=False)
    ts = P.now_us() - 1234
    desk.sock.sendall(desk.enc.encode(P.Heartbeat(P.Heartbeat.ROLE_DESK), timestamp_us=ts))
    hb = wait_until(lambda: [h for h in desk.of(P.MsgType.HEARTBEAT) if h.echo_ts_us == ts], 3)
    assert hb[0].role == P.Heartbeat.ROLE_ROBOT
    assert 0 <= hb[0].echo_hold_us < 1_500_000
    assert hb[0].rx_frames >= 1


def test_garbage_from_a_desk_is_counted_and_reported(robot, desk_factory):
    desk = desk_factory()
    wait_until(lambda: desk.of(P.MsgType.TELEMETRY))
    bad = bytearray(desk.enc.encode(P.Command("stop", {})))
    bad[-1] ^= 0xFF  # frame checksum wrong
    desk.sock.sendall(b"hello" + bytes(bad))
    seq = desk.send(P.Command("stop", {}))
    assert wait_until(lambda: desk.ack(seq)).ok
    ev = wait_until(lambda: desk.events("decoder_drop"), 3)
    assert ev[0].data["dropped"] >= 1 and ev[0].data["link"].startswith("tcp")


def test_every_desk_gets_the_streams(robot, desk_factory):
    a, b = desk_factory(), desk_factory()
    for d in (a, b):
        wait_until(lambda d=d: d.of(P.MsgType.TELEMETRY) and d.of(P.MsgType.POSE)
                   and d.of(P.MsgType.LIDAR_SCAN) and d.of(P.MsgType.HEARTBEAT))
    assert wait_until(lambda: len(a.events("client_connected")) >= 2)
