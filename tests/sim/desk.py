"""A plain-socket desk for tests of the robot process: a decoder thread keeps every
frame by type, a heartbeat thread keeps the link alive."""

from __future__ import annotations

import socket
import threading
import time

from waits import wait_until  # noqa: F401 - re-exported for the robot tests

from app.comm import auth
from app.comm import protocol as P


class SocketDesk:
    """A minimal desk: a socket, a FrameDecoder in a thread, frames kept by type.
    Commands are signed with the station key (``key``; default: the key file the
    tests point at) unless ``sign=False``."""

    def __init__(self, host: str, port: int, heartbeat: bool = True,
                 heartbeat_s: float = 0.25, sign: bool = True, key: bytes | None = None,
                 desk: str = "test-desk") -> None:
        self.sock = socket.create_connection((host, port), timeout=5)
        self.dec = P.FrameDecoder()
        self.signer = None
        if sign:
            self.signer = auth.CommandSigner(
                key if key is not None else auth.load_or_create_key()[0], desk)
        self.enc = P.FrameEncoder(signer=self.signer)
        self.frames: list[P.Frame] = []
        self.lock = threading.Condition()
        self.heartbeat = heartbeat
        self.heartbeat_s = heartbeat_s
        self._stop = threading.Event()
        self._rx = threading.Thread(target=self._read, daemon=True)
        self._rx.start()
        self._hb = threading.Thread(target=self._beat, daemon=True)
        self._hb.start()

    def _read(self) -> None:
        while not self._stop.is_set():
            try:
                data = self.sock.recv(65536)
            except OSError:
                return
            if not data:
                return
            fr = self.dec.feed(data)
            with self.lock:
                self.frames.extend(fr)
                self.lock.notify_all()

    def _beat(self) -> None:
        while not self._stop.wait(self.heartbeat_s):
            if self.heartbeat:
                self.send(P.Heartbeat(P.Heartbeat.ROLE_DESK))

    def send(self, msg) -> int:
        with self.lock:
            seq = self.enc.seq
            data = self.enc.encode(msg)
        try:
            self.sock.sendall(data)
        except OSError:
            pass
        return seq

    def of(self, t: P.MsgType) -> list:
        with self.lock:
            return [f.message for f in self.frames if f.msg_type == t]

    def events(self, code: str) -> list[P.Event]:
        return [e for e in self.of(P.MsgType.EVENT) if e.code == code]

    def wait_for(self, pred, timeout: float, what: str):
        """Wait for ``pred()`` to be truthy as frames arrive; name ``what`` on failure."""
        end = time.monotonic() + timeout
        with self.lock:
            while True:
                v = pred()
                if v:
                    return v
                left = end - time.monotonic()
                if left <= 0:
                    codes = [f.message.code for f in self.frames
                             if f.msg_type == P.MsgType.EVENT]
                    raise AssertionError(f"no {what} within {timeout} s; events: {codes}")
                self.lock.wait(min(left, 0.2))

    def ack(self, seq: int):
        for a in self.of(P.MsgType.COMMAND_ACK):
            if a.cmd_seq == seq:
                return a
        return None

    def close(self) -> None:
        self._stop.set()
        try:
            self.sock.close()
        except OSError:
            pass


