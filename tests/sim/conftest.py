"""Helpers for the simulated-robot tests: an in-process robot and a plain-socket desk."""

from __future__ import annotations

import socket
import threading
import time

import pytest

from app.comm import protocol as P
from sim_robot.config import SimConfig
from sim_robot.sim import SimRobot


def wait_until(pred, timeout: float = 5.0, interval: float = 0.01):
    """Poll ``pred`` until it returns something truthy; fail after ``timeout`` s."""
    end = time.monotonic() + timeout
    while True:
        v = pred()
        if v:
            return v
        if time.monotonic() > end:
            raise AssertionError(f"condition not met within {timeout} s")
        time.sleep(interval)


class Desk:
    """A minimal desk: a socket, a FrameDecoder in a thread, frames kept by type."""

    def __init__(self, host: str, port: int, heartbeat: bool = True) -> None:
        self.sock = socket.create_connection((host, port), timeout=5)
        self.dec = P.FrameDecoder()
        self.enc = P.FrameEncoder()
        self.frames: list[P.Frame] = []
        self.lock = threading.Lock()
        self.heartbeat = heartbeat
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

    def _beat(self) -> None:
        while not self._stop.wait(0.25):
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


@pytest.fixture
def robot():
    cfg = SimConfig(video=False, seed=3)
    r = SimRobot(cfg)
    r.start()
    yield r
    r.close()


@pytest.fixture
def desk_factory(robot):
    desks: list[Desk] = []

    def make(**kw) -> Desk:
        d = Desk(*robot.address, **kw)
        desks.append(d)
        return d

    yield make
    for d in desks:
        d.close()
