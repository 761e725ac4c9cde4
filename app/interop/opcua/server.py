"""The desk's OPC UA server, seen from the desk: a process of its own, fed from the
desk pipeline over a pipe, never in the desk's way and never stalled by it.

::

    desk process                                       server process ("opcua")
    DeskPipeline listeners ─ _post: a tuple (µs) ─▶ Sender thread ─ pipe ─▶ ServerCore
      values, mode, link_state, pose, patrol_status,  (batched, pickled)   (core.py)
      control, meter_record, alarm (+ its text)
    drain() ◀─────────────────────── pipe ◀───── calls: command, acknowledge, comment,
      └─▶ DeskCalls (desk_calls.py): lease checked,    shelve, unshelve; log records
          CommandGateway / AlarmMonitor, archive

Why a process: the server and the desk shared one interpreter's lock, and while the
desk's thread (Qt, the pipeline, the archive) ran, the server's loop could not; its
longest stall was 140-280 ms on a loaded machine. In its own process (started with
'spawn', as on Windows) only the operating system can stall it.

A listener only appends a tuple to a list; a thread of the desk pickles and writes what
gathered. The control room's calls come back over the other pipe and are run on the
desk's thread by :meth:`OpcUaDeskServer.drain` (the window and the headless desk call it
from a timer every 50 ms), which also hands the server's log records to the desk's
loggers. The server ends with the desk (:meth:`stop`, or the desk's process ending: see
child.py).
"""

from __future__ import annotations

import itertools
import logging
import multiprocessing
import pickle
import threading
import time
from pathlib import Path
from typing import Any
from urllib.parse import urlparse

from app.core.desk.channels import TELEMETRY_CHANNELS, battery_percent, mode_name
from app.core.freshness import FreshnessTracker
from app.interop.opcua import child
from app.interop.opcua.desk_calls import DeskCalls
from app.interop.opcua.users import UserStore
from app.interop.opcua.wire import Sender

__all__ = ["OpcUaDeskServer"]

log = logging.getLogger(__name__)

_KINDS = ("values", "mode", "link_state", "pose", "patrol_status", "control",
          "meter_record", "alarm")


def _message(kind: str, a: tuple) -> tuple:
    """A pipeline message as the server takes it: plain values (cheap to pickle, and
    nothing the server's process would need the desk's modules for), an alarm with its
    text in the desk's language."""
    if kind == "values":
        v = a[0]
        battery_v = v.get("battery_v")
        return (dict(v), None if battery_v is None else battery_percent(battery_v))
    if kind == "mode":
        return (int(a[0]), mode_name(a[0]))
    if kind == "link_state":
        return (str(a[0]),)
    if kind == "pose":
        p = a[0]
        return (float(p.x_m), float(p.y_m), float(p.theta_rad))
    if kind == "patrol_status":
        st = a[0]
        return (str(st.state), str(st.route), int(st.index), float(st.progress),
                str(st.reason))
    if kind == "control":
        c = a[0]
        return (str(getattr(c, "holder", None) or ""), bool(getattr(c, "mine", False)))
    if kind == "meter_record":
        r = a[0]
        return (str(r.gauge_id), str(r.unit), float(r.t),
                None if r.value is None else float(r.value), float(r.confidence),
                str(r.state), str(r.point))
    if kind == "alarm":
        tr = a[0]
        return (tr, tr.alarm.cleared_text if getattr(tr, "cleared", False) else tr.alarm.text)
    return a


def _log_levels() -> dict[str, int]:
    """The desk's levels of the loggers the server's process logs to (it sets its own
    loggers so, and sends the desk only what the desk would log)."""
    names = ["", "asyncua", "app", "app.interop", "app.interop.opcua"]
    names += [n for n in list(logging.root.manager.loggerDict)
              if n.startswith(("app.interop.opcua.", "asyncua."))]
    return {n: logging.getLogger(n or None).getEffectiveLevel() for n in names}


class OpcUaDeskServer:
    """``settings``: app.config.OpcuaSettings (``endpoint`` set). ``users``: the user
    store (default: the settings' users file). ``pki_dir``: where the desk's certificate
    lives when the settings do not say. ``freshness``: the tracker that judges staleness
    (default: the desk's rules, app/core/freshness.py)."""

    def __init__(self, settings: Any, *, users: UserStore | None = None,
                 pki_dir: str | Path = "", tick_s: float = 0.25, min_flush_s: float = 0.05,
                 freshness: FreshnessTracker | None = None, gc_freeze: bool = True,
                 cache_browsing: bool = True, fast_path: bool = True) -> None:
        self.settings = settings
        self.users = users if users is not None else UserStore(settings.users_file)
        self.pki_dir = Path(settings.pki_dir or pki_dir or "opcua-pki")
        self._options = {"tick_s": tick_s, "min_flush_s": min_flush_s,
                         "freshness": freshness, "gc_freeze": gc_freeze,
                         "cache_browsing": cache_browsing, "fast_path": fast_path}
        self.lease_mine = False  # the desk holds the robot's control lease (as it last heard)
        self.port: int | None = None
        self.pid: int | None = None
        self.drain_cpu_s = 0.0  # the desk thread's CPU in drain() (reading the pipe, calls)
        self._pipeline: Any = None
        self._calls: DeskCalls | None = None
        self._listeners: list[tuple[str, Any]] = []
        self._proc: Any = None
        self._send: Sender | None = None
        self._conn: Any = None  # the server → desk pipe's reading end
        self._read_lock = threading.Lock()
        self._ids = itertools.count(1)
        self._answers: dict[int, Any] = {}
        self._ready: tuple | None = None

    # ------------------------------------------------------------ desk side
    def attach(self, pipeline: Any) -> None:
        """Listen to ``pipeline`` (call on the desk's thread, before or after start);
        a pipeline attached before is no longer listened to, and the control room's
        calls go to this one."""
        self._detach()
        self._pipeline = pipeline
        self._calls = DeskCalls(pipeline, lambda: self.lease_mine)
        for kind in _KINDS:
            fn = (lambda k: lambda *a: self._post(k, a))(kind)
            pipeline.listen(kind, fn)
            self._listeners.append((kind, fn))
        self._post("link_state", (pipeline.link_state,))
        self._post("identity", (pipeline.robot_id(),))

    def detach(self) -> None:
        """Stop listening to the attached pipeline (on the desk's thread). The server
        keeps serving what it was told; the control room's calls are refused until a
        pipeline is attached again, and the desk is taken not to hold the lease."""
        self._detach()
        self._pipeline = self._calls = None
        self.lease_mine = False

    def _post(self, kind: str, args: tuple) -> None:
        if kind == "control":  # the desk's own view of the lease: it checks the calls
            self.lease_mine = bool(getattr(args[0], "mine", False))
        elif kind == "link_state" and args[0] != "connected":
            self.lease_mine = False  # the robot tells the lease anew on connecting
        send = self._send
        if send is None:
            return
        t = self._pipeline.latest_t if kind == "values" and self._pipeline else None
        send.post((kind, _message(kind, args), t or time.time(), time.monotonic()))

    def drain(self) -> int:
        """On the desk's thread: run the control room's calls, pass on the server's log
        records; returns how many calls ran."""
        c0 = time.thread_time()
        n = 0
        while (batch := self._read(0.0)) is not None:
            n += self._handle(batch)
        if self._calls is not None:
            self._calls.end_one_shots()
        self.drain_cpu_s += time.thread_time() - c0
        return n

    def _read(self, timeout_s: float) -> list[tuple] | None:
        """One batch from the server, waiting up to ``timeout_s``; None when none."""
        conn = self._conn
        if conn is None:
            return None
        with self._read_lock:
            try:
                if not conn.poll(timeout_s):
                    return None
                return pickle.loads(conn.recv_bytes())  # noqa: S301 - our own server
            except (EOFError, OSError):  # the server's process has ended
                self._conn = None
                conn.close()
                if self._ready is None:
                    self._ready = ("ready", None, "the server's process ended")
                return None

    def _handle(self, batch: list[tuple]) -> int:
        n = 0
        for msg in batch:
            kind = msg[0]
            if kind == "call":
                n += 1
                self._run_call(*msg[1:])
            elif kind == "log":
                rec = msg[1]
                logging.getLogger(rec.name).handle(rec)
            elif kind == "answer":
                self._answers[msg[1]] = msg[2]
            elif kind == "ready":
                self._ready = msg
        return n

    def _run_call(self, n: int, op: str, kw: dict[str, Any]) -> None:
        try:
            if self._calls is None:
                raise RuntimeError("no desk pipeline attached")
            reply = ("reply", n, True, self._calls.run(op, kw))
        except Exception as e:  # noqa: BLE001 - the caller is told, the desk goes on
            log.exception("OPC UA: %s from the control room failed", op)
            reply = ("reply", n, False, f"{type(e).__name__}: {e}")
        if self._send is not None:
            self._send.post(reply)

    @property
    def url(self) -> str:
        u = urlparse(self.settings.endpoint)
        host = u.hostname or "127.0.0.1"
        return f"opc.tcp://{host}:{self.port if self.port is not None else u.port}"

    # ------------------------------------------------------------ the process
    def start(self, timeout_s: float = 60.0) -> None:
        """Start the server's process and wait until it serves; raises RuntimeError
        with the reason when it cannot (the port taken, a bad certificate, ...)."""
        pipe = self._pipeline
        cfg = child.ServerConfig(
            settings=self.settings, users=self.users, pki_dir=self.pki_dir,
            configured=[(a, a.text) for a in pipe.monitor.configured()] if pipe else [],
            channels=[(c.key, c.unit, c.label) for c in TELEMETRY_CHANNELS],
            log_levels=_log_levels(), **self._options)
        ctx = multiprocessing.get_context("spawn")
        to_server, server_in = ctx.Pipe(duplex=False)[::-1]  # (writer, reader)
        desk_in, from_server = ctx.Pipe(duplex=False)
        self._proc = ctx.Process(target=child.main, args=(cfg, server_in, from_server),
                                 name="opcua", daemon=True)
        self._proc.start()
        self.pid = self._proc.pid
        server_in.close()  # the server's ends are its own: a closed pipe means it ended
        from_server.close()
        self._conn = desk_in
        self._send = Sender(to_server, "opcua-feed").start()
        end = time.monotonic() + timeout_s
        while self._ready is None and time.monotonic() < end:
            batch = self._read(0.1)
            if batch is not None:
                self._handle(batch)
            elif not self._proc.is_alive() and self._conn is None:
                break
        _, port, error = self._ready or ("ready", None, "it did not start in time")
        if port is None:
            self._detach()
            self._end_process(0.0)
            raise RuntimeError(f"OPC UA server could not start: {error}")
        self.port = port
        log.info("OPC UA server listening on %s (process %d)", self.url, self.pid)
        if pipe is not None:  # what the desk knew before the server ran
            self._post("link_state", (pipe.link_state,))
            self._post("identity", (pipe.robot_id(),))
            for a in pipe.monitor.listed():  # standing alarms: conditions now
                self._send.post(("alarm_state", (a, a.text), time.time(), time.monotonic()))

    def stop(self, timeout_s: float = 10.0) -> None:
        """Stop listening and end the server's process (it closes its sessions)."""
        self._detach()
        self._end_process(timeout_s)

    def _detach(self) -> None:
        for kind, fn in self._listeners:
            if self._pipeline is not None:
                self._pipeline.unlisten(kind, fn)
        self._listeners.clear()

    def _end_process(self, timeout_s: float) -> None:
        if self._send is not None:
            self._send.post(("stop",))
            self._send.close(min(timeout_s, 5.0))
        proc = self._proc
        if proc is not None:
            end = time.monotonic() + timeout_s
            while proc.is_alive() and time.monotonic() < end:  # its last log records
                batch = self._read(0.05)
                if batch is not None:
                    self._handle(batch)
            if proc.is_alive():
                log.warning("OPC UA server's process did not end: terminated")
                proc.terminate()
                proc.join(5.0)
        for conn in (self._conn, self._send.conn if self._send else None):
            if conn is not None:
                conn.close()
        self._conn, self._send, self._proc = None, None, None

    # ------------------------------------------------------------ figures
    def query(self, name: str, timeout_s: float = 30.0, **kw: Any) -> Any:
        """Ask the server's process (on the desk's thread; the calls that come
        meanwhile are run): ``stats``, ``watch`` (probe=bool), ``watched``,
        ``profile`` (path="" starts, a path stops and writes). See child.py."""
        if self._send is None:
            raise RuntimeError("the OPC UA server is not running")
        n = next(self._ids)
        self._send.post(("query", n, name, kw))
        end = time.monotonic() + timeout_s
        while n not in self._answers:
            if time.monotonic() > end or self._conn is None:
                raise RuntimeError(f"the OPC UA server did not answer {name}")
            batch = self._read(0.05)
            if batch is not None:
                self._handle(batch)
        value = self._answers.pop(n)
        if isinstance(value, Exception):
            raise value
        return value

    def stats(self) -> dict[str, Any]:
        """The server's counts (core.ServerCore.stats) and the desk's cost of feeding
        it: ``feed_cpu_s`` (the sender thread) and ``drain_cpu_s``."""
        out = self.query("stats")
        send = self._send
        out["feed_cpu_s"] = send.cpu_s if send is not None else 0.0
        out["drain_cpu_s"] = self.drain_cpu_s
        return out

    @property
    def refused_calls(self) -> int:
        """Control room calls refused (by role, or for the lease the desk checks)."""
        return int(self.stats()["refused_calls"])

    @property
    def max_stall_s(self) -> float:
        """The longest the server's loop was late waking up (an event-loop stall)."""
        return float(self.stats()["max_stall_s"])
