"""The patrol archive: one SQLite file (WAL), one writer thread, reads from any thread.

Every ``add_*`` method only puts an item on a queue and returns; the writer thread
takes what has arrived every ``batch_interval_s`` (or sooner when ``batch_rows`` have
piled up) and writes it in one transaction. When a write fails (disk full, read-only
file, database locked by another program) the transaction is rolled back, the rows stay
in memory and are retried with a growing pause; ``on_status(ok, message)`` is called
once when writing starts failing and once when it recovers. The memory kept for failed
rows is bounded (``max_held_rows``); beyond it the oldest high-rate rows (telemetry,
poses) are dropped first, and every dropped row is counted in :meth:`Archive.stats`
and reported through ``on_status``.

Reads open their own connection per thread, so the GUI can query while the writer
writes. Nothing here imports Qt.
"""

from __future__ import annotations

import logging
import queue
import sqlite3
import threading
import time
from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from app.core.records.queries import ArchiveQueries, Series, _iso, bin_series, fmt_number
from app.core.records.retention import ArchiveRetention
from app.core.records.rows import ArchiveRows, _json
from app.core.records.scans import ScanDecimator
from app.core.records.schema import (
    APP_ID,
    SCHEMA,
    SCHEMA_VERSION,
    add_origin_column,
    add_session_columns,
)
from app.core.records.writer import _STOP, ArchiveWriter

log = logging.getLogger(__name__)

__all__ = ["Archive", "ArchiveError", "Series", "bin_series", "fmt_number"]

SQLITE_MAGIC = b"SQLite format 3\x00"


def _jpeg_or_image(x: Any) -> Any:
    """Bytes stay bytes; an image is kept (as it is: frames are never changed after
    decoding) for the writer to encode; nothing or empty is None."""
    if x is None:
        return None
    if isinstance(x, bytes | bytearray | memoryview):
        return bytes(x) or None
    return x


def _opt_float(v: Any) -> float | None:
    if v is None:
        return None
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


class ArchiveError(RuntimeError):
    """The archive file cannot be used (not an archive, damaged, newer schema, no access)."""


class Archive(ArchiveWriter, ArchiveRows, ArchiveRetention, ArchiveQueries):
    """The desk's SQLite archive. See the module docstring and docs/archive.md.

    The writer thread lives in :mod:`~app.core.records.writer`, its SQL in
    :mod:`~app.core.records.rows`, retention in :mod:`~app.core.records.retention`
    and the reads in :mod:`~app.core.records.queries`."""

    def __init__(self, path: str | Path, *, batch_interval_s: float = 0.25,
                 batch_rows: int = 5000, max_held_rows: int = 200_000,
                 on_status: Callable[[bool, str], None] | None = None,
                 retention_days: float | None = None, export_dir: str | Path | None = None,
                 prune_interval_s: float = 3600.0, busy_timeout_ms: int = 200,
                 retry_max_s: float = 5.0) -> None:
        self.path = Path(path)
        self.batch_interval_s = batch_interval_s
        self.batch_rows = batch_rows
        self.max_held_rows = max_held_rows
        self.on_status = on_status
        self.retention_days = retention_days
        self.export_dir = Path(export_dir) if export_dir is not None else None
        self.prune_interval_s = prune_interval_s
        self.busy_timeout_ms = busy_timeout_ms
        self.retry_max_s = retry_max_s
        self._check_and_create()
        self._q: queue.SimpleQueue = queue.SimpleQueue()
        self._lock = threading.Lock()  # guards the counters below
        self._written: dict[str, int] = {}
        self._dropped: dict[str, int] = {}
        self._failures = 0
        self._failing = False
        self._last_error = ""
        self._held_count = 0
        self._queued = 0
        self._pruned: dict[str, int] = {}
        self._exported: list[str] = []
        self._local = threading.local()
        self._readers: list[sqlite3.Connection] = []
        self._closed = False
        self.scans = ScanDecimator()  # which lidar scans are kept (one a second)
        self._writer_hooks: deque[tuple[Callable[[sqlite3.Connection], Any],
                                        threading.Event, list]] = deque()
        self.session_id: int | None = None  # rows written now belong to it (None: none)
        self._thread = threading.Thread(target=self._writer_main, name="archive-writer",
                                        daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ opening
    def _check_and_create(self) -> None:
        p = self.path
        try:
            p.parent.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise ArchiveError(f"cannot create the archive folder {p.parent}: {e}") from None
        if p.exists():
            if p.is_dir():
                raise ArchiveError(f"{p} is a folder, not an archive file")
            try:
                with open(p, "rb") as f:
                    head = f.read(16)
            except OSError as e:
                raise ArchiveError(f"cannot read the archive {p}: {e}") from None
            if head and head != SQLITE_MAGIC:
                raise ArchiveError(f"{p} is not a Station Patrol archive (not an SQLite "
                                   f"database); move it away or choose another --data-dir")
        try:
            con = sqlite3.connect(p, timeout=5.0)
            try:
                tables = {r[0] for r in con.execute(
                    "SELECT name FROM sqlite_master WHERE type='table'")}
                if tables:
                    if "meta" not in tables:
                        raise ArchiveError(f"{p} is an SQLite database of another program "
                                           f"(no Station Patrol tables); not touching it")
                    meta = dict(con.execute("SELECT key, value FROM meta"))
                    if meta.get("app") != APP_ID:
                        raise ArchiveError(f"{p} belongs to another program "
                                           f"(app={meta.get('app')!r}); not touching it")
                    version = int(meta.get("schema_version", "0"))
                    if version > SCHEMA_VERSION:
                        raise ArchiveError(f"{p} was written by a newer Station Patrol "
                                           f"(schema {version}, this one reads "
                                           f"{SCHEMA_VERSION})")
                mode = con.execute("PRAGMA journal_mode=WAL").fetchone()[0]
                if mode.lower() != "wal":
                    log.warning("archive %s: journal mode is %s, not WAL", p, mode)
                con.executescript(SCHEMA)
                add_session_columns(con)
                add_origin_column(con)
                con.execute("INSERT OR IGNORE INTO meta VALUES ('app', ?)", (APP_ID,))
                con.execute("INSERT OR REPLACE INTO meta VALUES ('schema_version', ?)",
                            (str(SCHEMA_VERSION),))
                con.execute("INSERT OR IGNORE INTO meta VALUES ('created_utc', ?)",
                            (_iso(time.time()),))
                con.commit()
            finally:
                con.close()
        except ArchiveError:
            raise
        except sqlite3.DatabaseError as e:
            raise ArchiveError(f"{p} cannot be opened as an archive ({e}); it may be "
                               f"damaged: move it away and the desk starts a new one") from None
        except OSError as e:
            raise ArchiveError(f"cannot open the archive {p}: {e}") from None

    # ------------------------------------------------------------------ sessions
    def begin_session(self, desk: str, robot: str = "", t: float | None = None) -> int:
        """Start a session of ``desk`` with ``robot``: every row written from now on
        belongs to it. Returns its number."""
        t = time.time() if t is None else float(t)

        def insert(con: sqlite3.Connection) -> int:
            return con.execute("INSERT INTO session(started_t, desk, robot) VALUES (?,?,?)",
                               (t, desk, robot)).lastrowid

        sid = int(self.call_in_writer(insert))
        self.session_id = sid
        log.info("archive %s: session %d (desk %s, robot %s)", self.path, sid, desk,
                 robot or "not yet known")
        return sid

    def set_session_robot(self, robot: str) -> None:
        """Name the robot of the current session (known once the link connects)."""
        if self.session_id is not None:
            self._put("session_robot", self.session_id, str(robot))

    # ------------------------------------------------------------------ writing
    def _put(self, kind: str, *args: Any) -> None:
        if self._closed:
            with self._lock:
                self._dropped[kind] = self._dropped.get(kind, 0) + 1
            log.warning("archive closed; a %s row was not stored", kind)
            return
        with self._lock:
            self._queued += 1
        self._q.put((kind, (*args, self.session_id)))  # the row's session, stamped now

    def add_telemetry(self, t: float, values: dict[str, float], seq: int | None = None) -> None:
        names = tuple(values)
        try:
            data = np.array([float(values[k]) for k in names], np.float64).tobytes()
        except (TypeError, ValueError) as e:
            with self._lock:
                self._dropped["bad_telemetry"] = self._dropped.get("bad_telemetry", 0) + 1
            log.warning("telemetry row not stored: a value is not a number (%s)", e)
            return
        self._put("telemetry", float(t), seq, names, data)

    def add_meter_reading(self, t: float, point: str, value: float | None, unit: str,
                          confidence: float | None, *, fused: bool, state: str | None,
                          error: str | None = None, snapshot_jpeg: bytes | Any = None) -> None:
        """``snapshot_jpeg``: JPEG bytes, or the RGB frame read (encoded in the writer)."""
        self._put("meter_reading", float(t), str(point), _opt_float(value), unit,
                  _opt_float(confidence), bool(fused), state, error,
                  _jpeg_or_image(snapshot_jpeg))

    def add_alarm_transition(self, record: dict) -> None:
        """``record``: the alarm manager's ``Transition.as_record()`` dict."""
        r = record

        def text(key: str) -> str | None:
            v = r.get(key)
            if v is None:
                return None
            return str(getattr(v, "name", v)) if not isinstance(v, str) else v

        t = _opt_float(r.get("t"))
        self._put(
            "alarm_transition", time.time() if t is None else t, text("alarm") or "?",
            text("source"), text("priority"), text("from_state"), text("to_state"),
            _opt_float(r.get("value")), _opt_float(r.get("limit")), text("unit"),
            text("text"), text("user"), text("reason"), text("origin"))

    def add_command(self, t: float, user: str | None, command: str, args: dict | None,
                    seq: int | None = None, acked: bool | None = None) -> None:
        self._put("command", float(t), user, str(command), _json(args or {}), seq, acked)

    def ack_command(self, seq: int, ok: bool, reason: str, t: float) -> None:
        self._put("ack", int(seq), bool(ok), reason, float(t))

    def add_event(self, t: float, kind: str, data: dict | None = None) -> None:
        self._put("event", float(t), str(kind), _json(data or {}))

    def add_pose(self, t: float, x: float, y: float, theta: float) -> None:
        self._put("pose", float(t), float(x), float(y), float(theta))

    def add_scan(self, t: float, angle_min: float, angle_increment: float,
                 range_max: float, ranges_m: Any) -> bool:
        """A lidar scan, kept when its decimator says so (app/core/records/scans.py):
        True when it goes into the archive."""
        kept = self.scans.take(float(t), angle_min, angle_increment, ranges_m)
        if kept is None:
            return False
        self._put("scan", float(t), kept[0], kept[1], float(range_max), kept[2])
        return True

    def add_snapshot(self, t: float, jpeg: bytes | Any, reason: str,
                     ref: str | None = None) -> None:
        """``jpeg``: JPEG bytes, or an RGB uint8 image, made into a small JPEG (at most
        320 px wide) in the writer thread."""
        self._put("snapshot", float(t), _jpeg_or_image(jpeg), str(reason), ref)

    def add_map(self, t: float, png: bytes) -> None:
        self._put("map", float(t), bytes(png))

    def add_path(self, t: float, kind: str, points) -> None:
        pts = np.asarray(points, np.float32).reshape(-1, 2)
        self._put("path", float(t), str(kind), pts.tobytes())

    def prune(self, before_t: float, *, export_dir: str | Path | None = None
              ) -> threading.Event:
        """Delete rows older than ``before_t`` (UTC s), in small chunks in the writer
        thread between write batches; with ``export_dir`` they are first written there as
        CSV files. The returned event is set when the pruning is done."""
        done = threading.Event()
        self._put("prune", float(before_t),
                  Path(export_dir) if export_dir is not None else None, done)
        return done

    def flush(self, timeout: float = 5.0) -> bool:
        """Wait until everything added so far is on disk; False on timeout (e.g. while
        writes are failing, the rows are still held)."""
        if self._closed or not self._thread.is_alive():
            return False
        ev = threading.Event()
        self._q.put(("flush", (ev,)))
        return ev.wait(timeout)

    def _end_session(self) -> None:
        if self.session_id is not None and not self._closed:
            self._put("session_end", self.session_id, time.time())

    def close(self, timeout: float = 10.0) -> None:
        """Write what is pending (within ``timeout``) and stop the writer."""
        if self._closed:
            return
        self._end_session()
        self._closed = True
        self._q.put((_STOP, ()))
        self._thread.join(timeout)
        if self._thread.is_alive():
            log.error("archive writer did not finish within %.0f s; %d rows not written",
                      timeout, self._held_count)
        for con in self._readers:
            try:
                con.close()
            except sqlite3.Error:
                pass
        self._readers.clear()

    def stats(self) -> dict[str, Any]:
        with self._lock:
            return {"written": dict(self._written), "pending": self._queued + self._held_count,
                    "held": self._held_count, "failures": self._failures,
                    "failing": self._failing, "last_error": self._last_error,
                    "dropped": dict(self._dropped), "pruned": dict(self._pruned),
                    "exported": list(self._exported)}

    def call_in_writer(self, fn: Callable[[sqlite3.Connection], Any],
                       timeout: float = 5.0) -> Any:
        """Run ``fn(connection)`` in the writer thread (maintenance, tests). Returns its
        result; raises what it raised or TimeoutError."""
        ev = threading.Event()
        box: list = []
        self._writer_hooks.append((fn, ev, box))
        self._q.put(("hook", ()))
        if not ev.wait(timeout):
            raise TimeoutError("the archive writer did not answer")
        if box and isinstance(box[0], BaseException):
            raise box[0]
        return box[0] if box else None
