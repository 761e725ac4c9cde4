"""The MCU model's end of the serial link, and the address the relay opens.

The relay always opens its MCU port with pyserial's :func:`serial.serial_for_url`, a real
board's device (``/dev/ttyUSB0``, ``COM3``) or the simulated board's address alike, so its
serial code path is the same for both. The simulated board is served on one of two ends,
chosen at run time (``sim-robot --mcu-link``):

* ``socket`` (the default, every platform): a loopback TCP listener; the relay opens
  ``socket://127.0.0.1:PORT``. One relay at a time; a relay that reconnects is accepted
  again.
* ``pty`` (Unix only): a pseudo-terminal pair in raw mode; the relay opens the slave's
  device name, so pyserial's POSIX tty driver (termios settings, as for a USB-serial
  board) is exercised too. ``tty`` is imported only when this end is asked for.

A port's :meth:`read` waits up to ``timeout_s`` and returns what arrived (``b""`` for
nothing); :meth:`write` raises :class:`BlockingIOError` when the bytes could not go out
(nobody reading, a full buffer) — the MCU thread drops and counts them, as a UART would.
"""

from __future__ import annotations

import errno
import logging
import os
import select
import socket
import time

log = logging.getLogger(__name__)

__all__ = ["FdPort", "McuPort", "SocketPort", "open_mcu_port", "KINDS"]

KINDS = ("socket", "pty")
SEND_TIMEOUT_S = 0.2  # a relay that stops reading for this long loses frames


class McuPort:
    """The board's end of a serial link (see the module docstring)."""

    url: str = ""

    def read(self, timeout_s: float) -> bytes:
        raise NotImplementedError

    def write(self, data: bytes) -> None:
        raise NotImplementedError

    def close(self) -> None:
        pass


class SocketPort(McuPort):
    """A loopback TCP listener standing in for the board's UART."""

    def __init__(self, host: str = "127.0.0.1") -> None:
        self._listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self._listener.bind((host, 0))
        self._listener.listen(1)
        self._listener.setblocking(False)
        self._client: socket.socket | None = None
        port = self._listener.getsockname()[1]
        self.url = f"socket://{host}:{port}"

    def _drop_client(self) -> None:
        if self._client is not None:
            self._client.close()
            self._client = None

    def read(self, timeout_s: float) -> bytes:
        if self._client is None:  # wait for the relay to connect
            ready, _, _ = select.select([self._listener], [], [], timeout_s)
            if ready:
                try:
                    client, _ = self._listener.accept()
                except BlockingIOError:
                    return b""
                client.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                client.settimeout(SEND_TIMEOUT_S)
                self._drop_client()
                self._client = client
            return b""
        ready, _, _ = select.select([self._client], [], [], timeout_s)
        if not ready:
            return b""
        try:
            data = self._client.recv(4096)
        except (BlockingIOError, TimeoutError):
            return b""
        except OSError as e:
            log.info("MCU link: the relay's connection failed (%s)", e)
            data = b""
        if not data:  # the relay closed its port: wait for it to reopen
            self._drop_client()
        return data

    def write(self, data: bytes) -> None:
        if self._client is None:
            raise BlockingIOError(errno.EAGAIN, "no relay connected")
        try:
            self._client.sendall(data)
        except TimeoutError as e:
            raise BlockingIOError(errno.EAGAIN, "the relay is not reading") from e
        except OSError as e:
            self._drop_client()
            raise BlockingIOError(errno.EAGAIN, f"the relay's connection failed: {e}") from e

    def close(self) -> None:
        self._drop_client()
        self._listener.close()


class FdPort(McuPort):
    """A file descriptor (a pty master) standing in for the board's UART (Unix)."""

    def __init__(self, fd: int, url: str = "", extra_fds: tuple[int, ...] = ()) -> None:
        self.fd = fd
        self.url = url
        self._fds = (fd, *extra_fds)
        os.set_blocking(fd, False)

    @classmethod
    def pty(cls) -> FdPort:
        """A raw pseudo-terminal pair; the relay opens the slave's device name."""
        try:
            import tty  # Unix only, and only for this end of the link
        except ImportError as e:
            raise RuntimeError("a pseudo-terminal needs a Unix system; use --mcu-link "
                               "socket") from e
        master, slave = os.openpty()
        tty.setraw(master)
        tty.setraw(slave)
        return cls(master, os.ttyname(slave), (slave,))

    def read(self, timeout_s: float) -> bytes:
        ready, _, _ = select.select([self.fd], [], [], timeout_s)
        if not ready:
            return b""
        try:
            return os.read(self.fd, 4096)
        except BlockingIOError:
            return b""
        except OSError as e:  # EIO: the slave side is not open (yet)
            if e.errno != errno.EIO:
                log.warning("MCU serial read failed: %s", e)
            time.sleep(0.01)  # not a busy loop while nobody holds the other side
            return b""

    def write(self, data: bytes) -> None:
        try:
            os.write(self.fd, data)
        except OSError as e:
            if e.errno not in (errno.EIO, errno.EAGAIN):
                log.warning("MCU serial write failed: %s", e)
            raise BlockingIOError(errno.EAGAIN, str(e)) from e

    def close(self) -> None:
        for fd in self._fds:
            try:
                os.close(fd)
            except OSError:
                pass


def open_mcu_port(kind: str = "socket") -> McuPort:
    """The simulated board's end of the link: ``socket`` or ``pty`` (see above)."""
    if kind == "socket":
        return SocketPort()
    if kind == "pty":
        return FdPort.pty()
    raise ValueError(f"unknown MCU link {kind!r} (known: {', '.join(KINDS)})")
