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


def test_a_peer_sending_only_garbage_is_declared_lost(qtbot, link):
    peer = GarbagePeer()
    stats = []
    link.stats_changed.connect(stats.append)
    try:
        link.connect_to("127.0.0.1", peer.port)
        qtbot.waitUntil(lambda: link.state == "connected", timeout=5000)
        # the peer never stops sending; before the fix any byte kept it "connected"
        qtbot.waitUntil(lambda: link.state in ("lost", "reconnecting"), timeout=6000)
        assert peer.sent > 0
        # the garbage was counted, and the reason for the loss says why
        qtbot.waitUntil(lambda: bool(stats) and stats[-1].state != "connected", timeout=3000)
        assert stats[-1].by_reason.get("garbage_bytes", 0) > 0
        assert "no valid frame" in stats[-1].last_error
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
