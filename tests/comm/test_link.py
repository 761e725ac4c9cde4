"""RobotLink against a scripted TCP peer: silence means lost, garbage is counted,
heartbeats give a round-trip time, held drive commands are renewed."""

import socket
import threading
import time

import pytest

from app.comm import protocol as P
from app.comm.link import LinkSettings, RobotLink

pytestmark = pytest.mark.gui


class Peer:
    """A one-connection TCP server run by a script function on a thread."""

    def __init__(self, script):
        self.srv = socket.create_server(("127.0.0.1", 0))
        self.port = self.srv.getsockname()[1]
        self.received = bytearray()
        self.holds: list[int] = []
        self.done = threading.Event()
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, args=(script,), daemon=True)
        self.thread.start()

    def _run(self, script):
        conn, _ = self.srv.accept()
        conn.settimeout(0.05)
        try:
            script(self, conn)
        finally:
            self.done.set()
            self.stop.wait(5)  # keep the connection open until the test is done
            conn.close()

    def read_for(self, conn, seconds):
        end = time.monotonic() + seconds
        while time.monotonic() < end and not self.stop.is_set():
            try:
                data = conn.recv(65536)
            except TimeoutError:
                continue
            if not data:
                return
            self.received += data

    def close(self):
        self.stop.set()
        self.srv.close()


@pytest.fixture
def link(qtbot):
    lk = RobotLink(LinkSettings(lost_after_s=0.6, reconnect_every_s=5.0))
    yield lk
    lk.shutdown()


def hello_then_silence(p, c):
    """One valid frame (the link is up), then nothing."""
    p.sent_at = time.monotonic()
    c.sendall(P.FrameEncoder().encode(P.Heartbeat(P.Heartbeat.ROLE_ROBOT)))
    p.read_for(c, 5)


def heartbeats(p, c):
    """A live peer: a heartbeat every 0.2 s, reading what the desk sends."""
    enc = P.FrameEncoder()
    for _ in range(25):
        if p.stop.is_set():
            return
        try:
            c.sendall(enc.encode(P.Heartbeat(P.Heartbeat.ROLE_ROBOT)))
        except OSError:
            return  # the desk went away
        p.read_for(c, 0.2)


def test_silent_peer_is_declared_lost(qtbot, link):
    peer = Peer(hello_then_silence)
    states: list[str] = []
    link.state_changed.connect(states.append)  # every transition, however briefly shown
    try:
        link.connect_to("127.0.0.1", peer.port)
        qtbot.waitUntil(lambda: "connected" in states, timeout=5000)
        qtbot.waitUntil(lambda: any(s in ("lost", "reconnecting")
                                    for s in states[states.index("connected"):]),
                        timeout=5000)
        # not before the silence limit (0.6 s) after the peer's only frame; seen
        # here no earlier than it happened, however late a loaded machine shows it
        assert time.monotonic() - peer.sent_at >= 0.55
    finally:
        peer.close()


def test_an_open_socket_is_not_a_link_until_a_valid_frame_arrives(qtbot, link):
    """A peer that accepts and says nothing is never shown connected; the link
    gives up on it after the silence limit and says why."""
    peer = Peer(lambda p, c: p.read_for(c, 5))
    states = []
    link.state_changed.connect(states.append)
    try:
        link.connect_to("127.0.0.1", peer.port)
        # the desk said hello on the open socket (heartbeat, control request) ...
        qtbot.waitUntil(lambda: len(peer.received) > 0, timeout=5000)
        # ... and after the silence limit dropped it and tries again
        qtbot.waitUntil(lambda: "no valid frame" in link.last_error, timeout=5000)
        assert "after connecting" in link.last_error
        assert "connected" not in states and link.state == "connecting"
    finally:
        peer.close()


def test_garbage_is_counted_and_real_frames_still_arrive(qtbot, link):
    enc = P.FrameEncoder()

    def script(p, c):
        c.sendall(b"\x00garbage\xa5\x5a\x01junk" + enc.encode(P.Telemetry(gas_lel_pct=4.5)))
        bad = bytearray(enc.encode(P.Pose(1, 2, 3, 0, 0)))
        bad[-1] ^= 0xFF
        c.sendall(bytes(bad) + enc.encode(P.Telemetry(gas_lel_pct=5.5)))
        p.read_for(c, 3)

    peer = Peer(script)
    got, stats = [], []
    link.telemetry_received.connect(got.append)
    link.stats_changed.connect(stats.append)
    try:
        link.connect_to("127.0.0.1", peer.port)
        qtbot.waitUntil(lambda: len(got) == 2, timeout=5000)
        assert [round(t.gas_lel_pct, 1) for t in got] == [4.5, 5.5]
        assert all(t.received_s > 0 for t in got)
        qtbot.waitUntil(lambda: bool(stats) and stats[-1].frames_dropped >= 2, timeout=5000)
        assert stats[-1].by_reason["bad_checksum"] >= 1
    finally:
        peer.close()


def test_heartbeat_echo_gives_round_trip_time(qtbot):
    link = RobotLink()  # default 3 s silence limit: this peer speaks once a second
    enc = P.FrameEncoder()

    def script(p, c):
        dec = P.FrameDecoder()
        end = time.monotonic() + 4
        c.sendall(enc.encode(P.Heartbeat(P.Heartbeat.ROLE_ROBOT)))
        pending = None  # (desk heartbeat timestamp, when it arrived)
        while time.monotonic() < end and not p.stop.is_set():
            try:
                data = c.recv(65536)
            except TimeoutError:
                # answer a held heartbeat once the peer has kept it >= 60 ms,
                # saying how long it held it
                if pending and time.monotonic() - pending[1] >= 0.06:
                    hold_us = int((time.monotonic() - pending[1]) * 1e6)
                    c.sendall(enc.encode(P.Heartbeat(P.Heartbeat.ROLE_ROBOT,
                                                     pending[0], hold_us)))
                    p.holds.append(hold_us)
                    pending = None
                continue
            if not data:
                return
            for f in dec.feed(data):
                if f.msg_type == P.MsgType.HEARTBEAT and f.message.echo_ts_us:
                    pending = (f.timestamp_us, time.monotonic())

    peer = Peer(script)
    stats = []
    link.stats_changed.connect(stats.append)
    try:
        link.connect_to("127.0.0.1", peer.port)
        qtbot.waitUntil(lambda: bool(stats) and stats[-1].rtt_ms is not None, timeout=6000)
        # the peer held each heartbeat >= 60 ms; that hold is not round-trip time
        assert peer.holds and min(peer.holds) >= 60_000
        assert 0 <= stats[-1].rtt_ms < 50
    finally:
        peer.close()
        link.shutdown()


def test_held_drive_is_renewed_and_stop_is_sent(qtbot, link):
    peer = Peer(heartbeats)
    try:
        link.connect_to("127.0.0.1", peer.port)
        qtbot.waitUntil(lambda: link.state == "connected", timeout=5000)
        link.drive(0.4, -0.1)

        def commands():
            return [f.message for f in P.FrameDecoder().feed(bytes(peer.received))
                    if f.msg_type == P.MsgType.COMMAND and f.message.name != "request_control"]

        qtbot.waitUntil(lambda: sum(c.name == "drive" for c in commands()) >= 3, timeout=5000)
        link.stop()
        qtbot.waitUntil(lambda: commands()[-1].name == "stop", timeout=3000)
        n = len(commands())
        assert commands()[0].args == {"linear_mps": 0.4, "angular_rps": -0.1}
        # after stop no more drive renewals
        qtbot.wait(500)
        assert len(commands()) == n
    finally:
        peer.close()
