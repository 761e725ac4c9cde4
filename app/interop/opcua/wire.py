"""The pipe between the desk and its OPC UA server process: batches of messages
(pickled tuples), one way per pipe (``multiprocessing.Pipe(duplex=False)``).

Whoever posts never waits on the pipe: :meth:`Sender.post` appends to a list (a few
microseconds on the poster's thread) and a sender thread pickles what gathered and
writes it as one batch, so a burst (ten meter records of one cycle) costs one write and
one wake-up on the other side, and a full pipe (the other side busy or stopped) holds
only the sender thread. :func:`read_batches` is the other side's reading thread.

Both ends work the same on Windows (named pipes) and POSIX (socket pairs); nothing
here needs the other side's event loop to support pipes (the Proactor loop does not).
"""

from __future__ import annotations

import logging
import pickle
import threading
import time
from collections.abc import Callable
from typing import Any

__all__ = ["DeskRefused", "Sender", "read_batches"]

log = logging.getLogger(__name__)


class DeskRefused(Exception):
    """The desk did not take a call from the server (no answer in time, or gone)."""


class Sender:
    """Sends what is posted over ``conn`` (a Connection's writing end) from a thread of
    its own, named ``name``. ``cpu_s``: the CPU time that thread has used (pickling
    and writing: what sending costs this process beyond the posts)."""

    def __init__(self, conn: Any, name: str) -> None:
        self.conn = conn
        self.batches = 0
        self.messages = 0
        self.cpu_s = 0.0
        self.broken = False
        self._pending: list[tuple] = []
        self._lock = threading.Lock()
        self._wake = threading.Event()
        self._closing = False
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)

    def start(self) -> Sender:
        self._thread.start()
        return self

    def post(self, msg: tuple) -> None:
        """Send ``msg`` soon (in order with the others); never blocks."""
        with self._lock:
            self._pending.append(msg)
        self._wake.set()

    def close(self, timeout_s: float = 5.0) -> None:
        """Send what is pending, then stop the thread (the connection stays open)."""
        self._closing = True
        self._wake.set()
        if self._thread.is_alive():
            self._thread.join(timeout_s)

    def _run(self) -> None:
        while True:
            self._wake.wait()
            c0 = time.thread_time()
            self._wake.clear()
            with self._lock:
                batch, self._pending = self._pending, []
            if batch and not self.broken:
                try:
                    self.conn.send_bytes(pickle.dumps(batch, pickle.HIGHEST_PROTOCOL))
                    self.batches += 1
                    self.messages += len(batch)
                except (OSError, EOFError, ValueError) as e:  # the other side has gone
                    self.broken = True
                    log.info("OPC UA pipe closed (%s): %d messages not sent", e, len(batch))
                except Exception:  # noqa: BLE001 - an odd message must not stop the pipe
                    log.exception("OPC UA pipe: a batch of %d messages not sent", len(batch))
            self.cpu_s += time.thread_time() - c0
            if self._closing and not self._pending:
                return


def read_batches(conn: Any, deliver: Callable[[list[tuple]], None],
                 on_end: Callable[[], None]) -> None:
    """Read batches from ``conn`` and hand each to ``deliver`` until the other side
    closes its end (it ended, or was killed), then call ``on_end``. Run it in a
    thread."""
    try:
        while True:
            data = conn.recv_bytes()
            try:
                batch = pickle.loads(data)  # noqa: S301 - our own other side, over our pipe
            except Exception:  # noqa: BLE001 - counted in the log, the pipe goes on
                log.exception("OPC UA pipe: a batch could not be read")
                continue
            deliver(batch)
    except (EOFError, OSError):
        pass
    finally:
        on_end()
