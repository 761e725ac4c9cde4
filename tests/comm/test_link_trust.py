"""RobotLink's side of the trusted link: signed commands, the control lease as
the robot reports it, the GUI half of the deadman, telemetry gaps."""

import time

import pytest

from app.comm import auth
from app.comm import protocol as P
from app.comm.link import LinkSettings, RobotLink
from sim_robot.config import SimConfig
from sim_robot.sim import SimRobot

from .test_link import Peer

pytestmark = pytest.mark.gui


@pytest.fixture
def robot():
    r = SimRobot(SimConfig(video=False, seed=3))
    r.start()
    yield r
    r.close()


def _link(name):
    return RobotLink(LinkSettings(desk_name=name, reconnect_every_s=5.0))


def test_commands_are_signed_and_a_second_desk_is_view_only(qtbot, robot):
    a, b = _link("desk-a"), _link("desk-b")
    try:
        a.connect_to(*robot.address)
        qtbot.waitUntil(lambda: a.control.mine, timeout=10000)
        b.connect_to(*robot.address)
        qtbot.waitUntil(lambda: b.control.holder == "desk-a", timeout=10000)
        assert b.control.view_only and not b.control.mine
        assert a.key_fingerprint == auth.fingerprint(auth.load_key())
        # b's drive is refused by the robot
        acks = []
        b.ack_received.connect(acks.append)
        b.drive(0.3, 0.0)
        qtbot.waitUntil(lambda: any(not k.ok and "view only" in k.reason for k in acks),
                        timeout=5000)
        b.stop()
        assert robot.relay.cmd_v == 0.0
        # b asks, a hands over
        b.request_control()
        qtbot.waitUntil(lambda: a.control.requested_by == "desk-b", timeout=5000)
        a.hand_over()
        qtbot.waitUntil(lambda: b.control.mine and a.control.view_only, timeout=5000)
        b.drive(0.3, 0.0)
        qtbot.waitUntil(lambda: robot.relay.cmd_v == pytest.approx(0.3), timeout=5000)
        b.stop()
        qtbot.waitUntil(lambda: robot.relay.cmd_v == 0.0, timeout=5000)
        assert robot.relay.guard.counts["unsigned"] == 0
    finally:
        a.shutdown()
        b.shutdown()


def test_a_frozen_window_stops_renewing_the_drive_so_the_deadman_stops_the_robot(qtbot,
                                                                                 robot):
    lk = _link("desk-a")
    try:
        lk.connect_to(*robot.address)
        qtbot.waitUntil(lambda: lk.control.mine, timeout=10000)
        lk.drive(0.3, 0.0)
        qtbot.waitUntil(lambda: robot.relay.cmd_v == pytest.approx(0.3), timeout=5000)
        qtbot.wait(800)  # renewals keep it going past the 0.5 s deadman
        assert robot.relay.cmd_v == pytest.approx(0.3)
        lk._alive_timer.stop()  # the GUI thread stops ticking, as a frozen window would
        qtbot.waitUntil(lambda: robot.relay.cmd_v == 0.0, timeout=5000)
        assert lk.state == "connected"  # the link itself is fine: the deadman did it
    finally:
        lk.shutdown()


def test_telemetry_gaps_and_reordering_are_counted(qtbot):
    enc = P.FrameEncoder()

    def script(p, c):
        c.sendall(enc.encode(P.Heartbeat(P.Heartbeat.ROLE_ROBOT)))
        for s in (10, 11, 14, 13, 15, 15, 16):
            c.sendall(enc.encode(P.Telemetry(mcu_time_ms=s, tel_seq=s)))
        p.read_for(c, 3)

    peer = Peer(script)
    lk = RobotLink(LinkSettings(reconnect_every_s=5.0))
    stats = []
    lk.stats_changed.connect(stats.append)
    try:
        lk.connect_to("127.0.0.1", peer.port)
        qtbot.waitUntil(lambda: bool(stats) and stats[-1].telemetry_lost == 2
                        and stats[-1].telemetry_reordered == 2, timeout=5000)
        # the commands the link sent on its own (request_control) are signed
        cmds = [f for f in P.FrameDecoder().feed(bytes(peer.received))
                if f.msg_type == P.MsgType.COMMAND]
        assert cmds and all(f.message.mac for f in cmds)
        guard = auth.CommandGuard(auth.load_key(), started_us=0)
        assert all(guard.check(f)[0] == "" for f in cmds)
    finally:
        peer.close()
        lk.shutdown()


class _Sock:
    """Stands in for the worker's socket: keeps what is written, in order."""

    def __init__(self) -> None:
        self.data = bytearray()

    def write(self, b: bytes) -> None:
        time.sleep(0)  # yield the GIL here, where a real socket's write would
        self.data += b


def test_frames_reach_the_socket_in_the_order_their_counters_were_sealed(tmp_path):
    """Commands sealed on the GUI thread and on the link thread at the same time
    must be written with rising counters, or the robot refuses one as a replay."""
    import threading

    from app.comm.link import _LinkWorker

    w = _LinkWorker(LinkSettings(key_file=str(tmp_path / "k.key")))
    w.sock, w.state = _Sock(), "connected"
    go = threading.Barrier(2)

    def sender(name: str) -> None:
        go.wait()
        for i in range(300):
            w.encode_queued(P.Command(name, {"i": i}))
            if i % 7 == 0:
                w.flush()

    threads = [threading.Thread(target=sender, args=(n,)) for n in ("gui", "worker")]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    w.flush()
    dec = P.FrameDecoder()
    ctrs = [fr.message.auth["ctr"] for fr in dec.feed(bytes(w.sock.data))]
    assert len(ctrs) == 600
    assert ctrs == sorted(ctrs) and len(set(ctrs)) == 600
