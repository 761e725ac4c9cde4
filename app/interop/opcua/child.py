"""The OPC UA server's process: started by the desk (``multiprocessing``, start method
'spawn', so it starts the same way on Windows, macOS and Linux), it runs
:class:`~app.interop.opcua.core.ServerCore` on an asyncio loop of its own, with its own
interpreter and GIL: nothing the desk does can stall it, and nothing it does can stall
the desk.

Threads of the process: the loop (the server), ``opcua-in`` reading the desk's batches
(:func:`~app.interop.opcua.wire.read_batches`, handing each to the loop),
``opcua-out`` writing to the desk (:class:`~app.interop.opcua.wire.Sender`: answers,
calls, log records), ``opcua-parent`` waiting for the desk's process to end.

It ends when the desk says so (``("stop",)``), when the desk closes its end of the pipe,
or when the desk's process ends in any way, killed too (the parent's sentinel, which
the operating system signals): a server never outlives its desk.

Its log records go to the desk (``("log", record)``), which hands them to its own
loggers, so the desk's log files and console have them as before.
"""

from __future__ import annotations

import asyncio
import collections
import cProfile
import dataclasses
import errno
import logging
import multiprocessing
import multiprocessing.connection
import signal
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from app.interop.opcua.wire import Sender, read_batches

__all__ = ["ServerConfig", "main"]

log = logging.getLogger(__name__)

_WSAEADDRINUSE = 10048  # Windows' "address already in use"


@dataclass
class ServerConfig:
    """What the server's process is started with (pickled to it). ``configured``:
    every alarm the desk's rules can raise, with its text in the desk's language;
    ``channels``: the telemetry channels (the server's process does not import the
    desk's pipeline: some 40 MB of modules it does not use)."""

    settings: Any  # app.config.OpcuaSettings
    users: Any  # app.interop.opcua.users.UserStore
    pki_dir: Path
    tick_s: float = 0.25
    min_flush_s: float = 0.05
    freshness: Any = None  # app.core.freshness.FreshnessTracker (None: the desk's rules)
    gc_freeze: bool = True
    cache_browsing: bool = True
    fast_path: bool = True  # fast_path.py installed
    cache_address_space: bool = True  # aspace_cache.py: the standard nodes from a shelf
    configured: list[tuple[Any, str]] = field(default_factory=list)
    channels: list[tuple[str, str, str]] = field(default_factory=list)  # key, unit, label
    log_levels: dict[str, int] = field(default_factory=dict)  # logger name -> level


class _ToDesk(logging.Handler):
    """Sends each log record to the desk, its message made (as QueueHandler does)."""

    def __init__(self, out: Sender) -> None:
        super().__init__()
        self.out = out

    def emit(self, record: logging.LogRecord) -> None:
        try:
            msg = self.format(record)
            record = logging.makeLogRecord(record.__dict__)
            record.msg, record.args, record.exc_info, record.exc_text = msg, None, None, None
            record.stack_info = None
            self.out.post(("log", record))
        except Exception:  # noqa: BLE001 - logging must never stop the server
            self.handleError(record)


def main(cfg: ServerConfig, inbox: Any, outbox: Any) -> None:
    """The process's entry: serve until the desk stops it or ends."""
    # Ctrl+C in the desk's terminal reaches every process of the console: the desk
    # decides when its server ends
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    out = Sender(outbox, "opcua-out").start()
    root = logging.getLogger()
    root.handlers[:] = [_ToDesk(out)]
    for name, level in cfg.log_levels.items():
        logging.getLogger(name or None).setLevel(level)
    try:
        asyncio.run(_serve(cfg, inbox, out))
    finally:
        out.close()


class _Figures:
    """A bench's or a test's questions to the server (``("query", id, name, kw)``),
    answered on the loop with ``("answer", id, value)``."""

    def __init__(self, core: Any, out: Sender) -> None:
        self.core, self.out = core, out
        self.gcp: Any = None
        self.probe: Any = None
        self.profile: cProfile.Profile | None = None

    def answer(self, n: int, name: str, kw: dict[str, Any]) -> None:
        try:
            value = getattr(self, f"q_{name}")(**kw)
        except Exception as e:  # noqa: BLE001 - told to the asker
            log.exception("OPC UA: query %s failed", name)
            value = RuntimeError(f"{name}: {type(e).__name__}: {e}")
        self.out.post(("answer", n, value))

    def q_stats(self) -> dict[str, Any]:
        return self.core.stats()

    def q_imported(self, module: str) -> bool:
        """Whether ``module`` is loaded in the server's process."""
        return module in sys.modules

    def q_watch(self, probe: bool = False) -> None:
        """From now: the loop's stalls with the process's collections, and (``probe``)
        every callback of the loop timed."""
        from app.interop.opcua.loop_probe import CallbackProbe, GcProbe
        self.gcp = GcProbe().__enter__()
        self.core.stalls.gc_probe = self.gcp
        self.core.stalls.reset()
        self.probe = CallbackProbe().install() if probe else None

    def q_watched(self) -> tuple[Any, Any, Any, str]:
        """(stalls, collections, callbacks or None, a full collection now) since
        :meth:`q_watch`."""
        from app.interop.opcua.loop_probe import full_collection
        self.gcp.__exit__()
        st = self.core.stalls
        seen = dataclasses.replace(st, recent=collections.deque(st.recent), gc_probe=None)
        if self.probe is not None:
            self.probe.uninstall()
        return seen, self.gcp, self.probe, full_collection()

    def q_profile(self, path: str = "") -> None:
        """Start a cProfile of the loop (no ``path``), or stop it and write it there.
        Timed in the loop thread's CPU (``time.thread_time``), not wall clock: on a
        shared machine the wall time of a call holds the time other processes ran."""
        if not path:
            self.profile = cProfile.Profile(time.thread_time)
            self.profile.enable()
        elif self.profile is not None:
            self.profile.disable()
            self.profile.dump_stats(path)


async def _serve(cfg: ServerConfig, inbox: Any, out: Sender) -> None:
    from app.interop.opcua.core import ServerCore
    loop = asyncio.get_running_loop()
    core = ServerCore(cfg, out.post)
    figures = _Figures(core, out)

    def receive(batch: list[tuple]) -> None:  # on the loop
        rest = []
        for msg in batch:
            if msg[0] == "query":
                figures.answer(*msg[1:])
            else:
                rest.append(msg)
        core.receive(rest)

    def ended() -> None:  # from a thread: the desk has gone
        try:
            loop.call_soon_threadsafe(core.stop)
        except RuntimeError:  # the loop has closed already
            pass

    threading.Thread(target=read_batches, args=(inbox, lambda b: loop.call_soon_threadsafe(
        receive, b), ended), name="opcua-in", daemon=True).start()
    parent = multiprocessing.parent_process()
    if parent is not None:
        def watch() -> None:
            multiprocessing.connection.wait([parent.sentinel])
            log.info("OPC UA: the desk's process has ended: the server stops")
            ended()
        threading.Thread(target=watch, name="opcua-parent", daemon=True).start()
    try:
        await core.main(on_ready=lambda port: out.post(("ready", port, None)))
    except Exception as e:  # noqa: BLE001 - told to the desk, which says why it cannot start
        log.debug("OPC UA server failed", exc_info=True)
        out.post(("ready", None, why_not(e, cfg.settings.endpoint)))


def why_not(e: Exception, endpoint: str) -> str:
    """Why the server could not start, in words: a port in use is named as such."""
    if isinstance(e, OSError) and e.errno in (errno.EADDRINUSE, _WSAEADDRINUSE):
        return (f"{endpoint}: the port is in use by another program (or another desk); "
                f"choose another port in [opcua] endpoint or --opcua")
    return f"{type(e).__name__}: {e}"
