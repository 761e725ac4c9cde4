"""A peer that sends only bytes that never decode is lost, like a silent one:
only a valid frame refreshes the link's watchdog (issue 12, A.3)."""

import os
import socket
import threading

import pytest

from app.comm import protocol as P
from app.comm.link import LinkSettings, RobotLink

pytestmark = pytest.mark.gui


class GarbagePeer:
    """Accepts one desk, then sends undecodable bytes (random noise and frames
    with a broken header) until told to stop; optionally one valid frame first."""

    def __init__(self, first_frame: bytes = b"") -> None:
        self.srv = socket.create_server(("127.0.0.1", 0))  # port 0: a free port
        self.port = self.srv.getsockname()[1]
        self.first = first_frame
        self.sent = 0
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        conn, _ = self.srv.accept()
        enc = P.FrameEncoder()
        try:
            if self.first:
                conn.sendall(self.first)
            while not self.stop.is_set():
                bad = bytearray(enc.encode(P.Telemetry(gas_lel_pct=1.0)))
                bad[2] ^= 0xFF  # a broken header: the frame never decodes
                chunk = os.urandom(4096) + bytes(bad)
                try:
                    conn.sendall(chunk)
                except OSError:
                    return  # the desk gave up on us: that is the point
                self.sent += len(chunk)
                self.stop.wait(0.01)
        finally:
            conn.close()

    def close(self) -> None:
        self.stop.set()
        self.srv.close()
        self.thread.join(5)


@pytest.fixture
def link(qtbot):
    lk = RobotLink(LinkSettings(lost_after_s=0.8, reconnect_every_s=30.0))
    yield lk
    lk.shutdown()


def test_a_peer_sending_only_garbage_is_never_connected(qtbot, link):
    peer = GarbagePeer()
    stats, states = [], []
    link.stats_changed.connect(stats.append)
    link.state_changed.connect(states.append)
    try:
        link.connect_to("127.0.0.1", peer.port)
        # the peer never stops sending; any byte once kept it "connected", and an
        # open socket once was "connected" before a single valid frame came
        qtbot.waitUntil(lambda: bool(stats) and "no valid frame" in stats[-1].last_error,
                        timeout=6000)
        assert peer.sent > 0
        # the garbage was counted, and the reason says why
        assert stats[-1].by_reason.get("garbage_bytes", 0) > 0
        assert "connected" not in states
    finally:
        peer.close()


def test_valid_frame_then_garbage_is_still_lost(qtbot, link):
    """One good telemetry frame, then only noise: the good frame is delivered,
    the noise that follows does not keep the link alive."""
    enc = P.FrameEncoder()
    peer = GarbagePeer(enc.encode(P.Telemetry(gas_lel_pct=7.5)))
    got = []
    link.telemetry_received.connect(got.append)
    try:
        link.connect_to("127.0.0.1", peer.port)
        qtbot.waitUntil(lambda: len(got) == 1, timeout=5000)
        assert round(got[0].gas_lel_pct, 1) == 7.5
        qtbot.waitUntil(lambda: link.state in ("lost", "reconnecting"), timeout=6000)
        assert peer.sent > 0
    finally:
        peer.close()


class ReconnectingGarbagePeer:
    """Accepts desk after desk: the first connection gets one valid heartbeat, then
    noise; every later one gets noise only. Counts the connections."""

    def __init__(self) -> None:
        self.srv = socket.create_server(("127.0.0.1", 0))
        self.port = self.srv.getsockname()[1]
        self.accepted = 0
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        enc = P.FrameEncoder()
        while not self.stop.is_set():
            try:
                conn, _ = self.srv.accept()
            except OSError:
                return  # closed
            self.accepted += 1
            try:
                if self.accepted == 1:
                    conn.sendall(enc.encode(P.Heartbeat(P.Heartbeat.ROLE_ROBOT)))
                while not self.stop.is_set():
                    bad = bytearray(enc.encode(P.Heartbeat(P.Heartbeat.ROLE_ROBOT)))
                    bad[2] ^= 0xFF
                    conn.sendall(os.urandom(2048) + bytes(bad))
                    self.stop.wait(0.01)
            except OSError:
                pass  # the desk dropped this connection: wait for the next
            finally:
                conn.close()

    def close(self) -> None:
        self.stop.set()
        self.srv.close()
        self.thread.join(5)


def test_reconnects_to_a_garbage_peer_raise_link_lost_once_and_never_clear_it(qtbot):
    """A.3 follow-up: the link is lost, and each reconnect finds a peer sending only
    garbage. The open socket must not count as "connected" (which cleared the
    link-lost alarm until the watchdog raised it again: a flapping alarm)."""
    from app.session import DeskSession

    link = RobotLink(LinkSettings(lost_after_s=0.5, reconnect_every_s=0.1))
    desk = DeskSession(link)
    transitions, states, restored = [], [], []
    desk.pipeline.listen("alarm", lambda tr: transitions.append(tr)
                         if tr.alarm.key == "link.lost" else None)
    link.state_changed.connect(states.append)
    link.link_restored.connect(lambda: restored.append(True))
    peer = ReconnectingGarbagePeer()
    try:
        link.connect_to("127.0.0.1", peer.port)
        qtbot.waitUntil(lambda: "connected" in states, timeout=5000)
        qtbot.waitUntil(lambda: desk.monitor.is_active("link.lost"), timeout=5000)
        # reconnects to a peer that sends only garbage, each given up on: the third
        # connection was dropped once the fourth is accepted
        qtbot.waitUntil(lambda: peer.accepted >= 4, timeout=10000)
        assert states.count("connected") == 1  # the first connection only
        assert restored == [] and desk.pipeline.restored_count == 0
        assert desk.monitor.is_active("link.lost")
        assert sum(tr.raised for tr in transitions) == 1
        assert not any(tr.cleared for tr in transitions)
    finally:
        peer.close()
        desk.close()
        link.shutdown()
