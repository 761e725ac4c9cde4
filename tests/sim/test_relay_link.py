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


def test_garbage_on_the_mcu_serial_line_is_counted_and_reports_keep_coming(robot,
                                                                             desk_factory):
    import random

    from sim_robot import mcu_link as M

    desk = desk_factory()
    wait_until(lambda: desk.of(P.MsgType.TELEMETRY))
    port = robot.mcu_port  # the MCU's end of the serial line (socket or pty)
    rng = random.Random(4)
    junk = [rng.randbytes(300),
            M.SYNC + bytes((M.McuType.SENSOR_REPORT, 1, 3)) + b"abc\x00\x00",  # wrong length
            M.McuEncoder().encode(M.Keepalive())[:-1],  # cut short
            M.SYNC * 40,
            M.encode_frame(0x7E, 1, b"")]  # unknown type
    for j in junk:
        port.write(j)
    reports = robot.relay.mcu_reports
    ev = desk.wait_for(lambda: [e for e in desk.events("rejections")
                                if any(k.startswith("mcu:") for k in e.data["counts"])], 5,
                       "MCU serial refusals in the robot's counts")
    counts = ev[-1].data["counts"]
    assert counts.get("mcu:bad_length", 0) + counts.get("mcu:unknown_type", 0) >= 2
    wait_until(lambda: robot.relay.mcu_reports > reports + 20, 5)  # still reporting
    n = len(desk.of(P.MsgType.TELEMETRY))
    wait_until(lambda: len(desk.of(P.MsgType.TELEMETRY)) > n + 5, 5)
