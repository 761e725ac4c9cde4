"""The MCU model's end of the serial link: a loopback socket everywhere, a pty on Unix;
the relay opens either with pyserial's serial_for_url, as it opens a real board."""

from __future__ import annotations

import os

import pytest
import serial

from sim_robot.config import SimConfig
from sim_robot.mcu_port import open_mcu_port
from sim_robot.sim import SimRobot, open_serial
from tests.waits import wait_until


def _read_until(port, want: bytes) -> bytes:
    got = b""

    def more():
        nonlocal got
        got += port.read(0.05)
        return want in got

    wait_until(more, timeout=5.0, what=f"{want!r} at the board's end")
    return got


def _exchange(board, url: str) -> None:
    relay = open_serial(url, 115200)
    try:
        relay.write(b"keepalive")
        assert b"keepalive" in _read_until(board, b"keepalive")
        board.write(b"report")
        got = b""

        def arrived():
            nonlocal got
            got += relay.read(max(1, relay.in_waiting))
            return b"report" in got

        wait_until(arrived, timeout=5.0, what="the board's bytes at the relay")
    finally:
        relay.close()


def test_socket_end_talks_to_pyserial_and_takes_a_reconnect():
    board = open_mcu_port("socket")
    try:
        assert board.url.startswith("socket://127.0.0.1:")
        with pytest.raises(BlockingIOError):
            board.write(b"nobody listens")  # dropped and counted by the MCU thread
        _exchange(board, board.url)
        # the relay closed its port (as on a serial error) and opens it again
        wait_until(lambda: board.read(0.05) == b"" and board._client is None, timeout=5.0,
                   what="the board noticing the relay left")
        _exchange(board, board.url)
    finally:
        board.close()


@pytest.mark.skipif(not hasattr(os, "openpty"), reason="pseudo-terminals are Unix-only")
def test_pty_end_talks_to_pyserial():
    board = open_mcu_port("pty")
    try:
        assert board.url.startswith("/dev/")
        _exchange(board, board.url)
    finally:
        board.close()


def test_unknown_link_is_refused_by_name():
    with pytest.raises(ValueError, match="unknown MCU link 'usb'"):
        open_mcu_port("usb")


@pytest.mark.parametrize("kind", ["socket", "pty"])
def test_relay_gets_the_model_reports_over_either_end(kind):
    if kind == "pty" and not hasattr(os, "openpty"):
        pytest.skip("pseudo-terminals are Unix-only")
    r = SimRobot(SimConfig(video=False, seed=3, mcu_link=kind))
    try:
        r.start()
        wait_until(lambda: r.relay.mcu_reports >= 5, timeout=60.0,
                   what=f"MCU reports at the relay over the {kind} end")
        assert isinstance(r.relay.port, serial.SerialBase)  # the same pyserial path as a board
        assert r.mcu_thread.model.report.mcu_time_ms > 0
    finally:
        r.close()


def test_the_relay_reads_a_burst_from_the_socket_port_in_a_few_reads():
    """pyserial's socket:// says ``in_waiting == 1`` for "some bytes": reading that
    many took one byte per call, and a stream of reports fell seconds behind."""
    from sim_robot.relay.serial_bridge import read_waiting

    board = open_mcu_port("socket")
    relay = open_serial(board.url, 115200)
    try:
        relay.write(b"hello")
        _read_until(board, b"hello")  # the board has accepted the relay
        burst = bytes(range(256)) * 40  # 10 KB, about 200 sensor reports
        board.write(burst)
        got, reads = b"", 0
        while len(got) < len(burst) and reads < 1000:
            got += read_waiting(relay)
            reads += 1
        assert got == burst
        assert reads <= 20, f"{reads} reads for 10 KB"
        relay.timeout = 0.05
        assert read_waiting(relay) == b""  # nothing waiting: empty after the timeout
        assert relay.timeout == 0.05  # the port's own timeout is kept
    finally:
        relay.close()
        board.close()
