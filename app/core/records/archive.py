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

import csv
import json
import logging
import math
import queue
import sqlite3
import threading
import time
from collections import deque
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from app.core.records.queries import ArchiveQueries, Series, _iso, bin_series, fmt_number
from app.core.records.scans import ScanDecimator
from app.core.records.schema import (
    APP_ID,
    ROLLUP_LEVELS_S,
    SCHEMA,
    SCHEMA_VERSION,
    TIMED_TABLES,
    add_origin_column,
    add_session_columns,
)

log = logging.getLogger(__name__)

__all__ = ["Archive", "ArchiveError", "Series", "bin_series", "fmt_number"]

SQLITE_MAGIC = b"SQLite format 3\x00"
BULK_KINDS = frozenset({"telemetry", "pose"})
_STOP = object()


# errors that dropping the row fixes (SQLite refused a value), unlike a full, locked or
# read-only disk, which retrying fixes
BAD_ITEM = (sqlite3.InterfaceError, sqlite3.ProgrammingError, sqlite3.DataError,
            sqlite3.IntegrityError, TypeError, ValueError, KeyError, OverflowError)
SNAPSHOT_WIDTH_PX = 320
SNAPSHOT_QUALITY = 70


def small_jpeg(image: Any, width: int = SNAPSHOT_WIDTH_PX) -> bytes | None:
    """A small JPEG (at most ``width`` px wide) of an RGB uint8 image, or None."""
    try:
        import cv2

        img = np.asarray(image)
        if img.dtype != np.uint8 or img.ndim != 3 or img.shape[2] != 3 or not img.size:
            return None
        h, w = img.shape[:2]
        if w > width:
            img = cv2.resize(img, (width, max(1, round(h * width / w))),
                             interpolation=cv2.INTER_AREA)
        ok, buf = cv2.imencode(".jpg", cv2.cvtColor(img, cv2.COLOR_RGB2BGR),
                               [cv2.IMWRITE_JPEG_QUALITY, SNAPSHOT_QUALITY])
        return buf.tobytes() if ok else None
    except Exception as e:  # a snapshot is a convenience; never stop recording
        log.warning("could not make a snapshot: %s", e)
        return None


def _jpeg_or_image(x: Any) -> Any:
    """Bytes stay bytes; an image is kept (as it is: frames are never changed after
    decoding) for the writer to encode; nothing or empty is None."""
    if x is None:
        return None
    if isinstance(x, bytes | bytearray | memoryview):
        return bytes(x) or None
    return x


def _rollback(con: sqlite3.Connection) -> None:
    try:
        con.execute("ROLLBACK")
    except sqlite3.Error:
        pass


def _opt_float(v: Any) -> float | None:
    if v is None:
        return None
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


class ArchiveError(RuntimeError):
    """The archive file cannot be used (not an archive, damaged, newer schema, no access)."""


def _json(d: Any) -> str:
    return json.dumps(d, default=str, separators=(",", ":"))


class Archive(ArchiveQueries):
    """The desk's SQLite archive. See the module docstring and docs/archive.md."""

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

    # ------------------------------------------------------------ writer thread
    def _connect_writer(self) -> sqlite3.Connection:
        con = sqlite3.connect(self.path, timeout=self.busy_timeout_ms / 1000.0,
                              isolation_level=None, check_same_thread=False)
        con.execute(f"PRAGMA busy_timeout={int(self.busy_timeout_ms)}")
        con.execute("PRAGMA journal_mode=WAL")
        con.execute("PRAGMA synchronous=NORMAL")
        return con

    def _writer_main(self) -> None:
        try:
            self._writer_loop()
        except Exception as e:  # a bug: say so loudly; later rows are counted as dropped
            self._closed = True
            with self._lock:
                held = self._held_count
                self._dropped["writer_stopped"] = held
            msg = f"archive writer stopped by an error ({e!r}); {held} rows not written"
            log.exception(msg)
            self._notify(False, msg)

    def _writer_loop(self) -> None:
        con: sqlite3.Connection | None = None
        self._chan_ids: dict[str, int] = {}
        self._layout_ids: dict[tuple[str, ...], tuple[int, list[int]]] = {}
        bulk: deque = deque()
        precious: deque = deque()
        flushes: list[threading.Event] = []
        prune_jobs: deque = deque()
        next_retry = 0.0
        backoff = 0.25
        attempts = 0
        stopping = False
        next_auto_prune = time.monotonic()
        while True:
            # 1. gather what has arrived (up to one batch interval)
            deadline = time.monotonic() + (0.01 if prune_jobs else self.batch_interval_s)
            got = 0
            while not stopping:
                timeout = deadline - time.monotonic()
                try:
                    item = self._q.get(timeout=max(0.0, timeout)) if timeout > 0 \
                        else self._q.get_nowait()
                except queue.Empty:
                    break
                kind, args = item
                if kind is _STOP:
                    stopping = True
                    break
                if kind == "flush":
                    flushes.append(args[0])
                    break
                if kind == "hook":
                    if con is None:
                        con = self._try_connect()
                    self._run_hook(con)
                    continue
                if kind == "prune":
                    with self._lock:
                        self._queued -= 1
                    prune_jobs.append([args[0], args[1], args[2]])
                    continue
                if kind in ("snapshot", "meter_reading"):
                    item = self._encode_image(kind, args)
                (bulk if kind in BULK_KINDS else precious).append(item)
                got += 1
                with self._lock:
                    self._queued -= 1
                    self._held_count += 1
                if got >= self.batch_rows:
                    break
            if stopping:  # take everything still queued
                while True:
                    try:
                        kind, args = self._q.get_nowait()
                    except queue.Empty:
                        break
                    if kind in ("flush",):
                        flushes.append(args[0])
                    elif kind == "hook":
                        self._run_hook(con)
                    elif kind not in ("prune",) and kind is not _STOP:
                        item = (kind, args)
                        if kind in ("snapshot", "meter_reading"):
                            item = self._encode_image(kind, args)
                        (bulk if kind in BULK_KINDS else precious).append(item)
                        with self._lock:
                            self._queued -= 1
                            self._held_count += 1
            self._enforce_bound(bulk, precious)
            # 2. automatic retention
            if self.retention_days is not None and time.monotonic() >= next_auto_prune:
                next_auto_prune = time.monotonic() + self.prune_interval_s
                prune_jobs.append([time.time() - self.retention_days * 86400.0,
                                   self.export_dir, threading.Event()])
            # 3. write (or retry) what is held
            now = time.monotonic()
            if (bulk or precious) and now >= next_retry:
                if con is None:
                    con = self._try_connect()
                ok = con is not None and self._write_held(con, bulk, precious)
                if ok:
                    attempts = 0
                    backoff = 0.25
                else:
                    attempts += 1
                    next_retry = time.monotonic() + backoff
                    backoff = min(backoff * 2, self.retry_max_s)
                    if attempts % 5 == 0 and con is not None:  # the file may have changed
                        try:
                            con.close()
                        except sqlite3.Error:
                            pass
                        con = None
            if not bulk and not precious:
                for ev in flushes:
                    ev.set()
                flushes.clear()
                # 4. retention: one small chunk per round, so writes keep flowing
                if prune_jobs and con is None:
                    con = self._try_connect()
                if prune_jobs and con is not None and not self._failing:
                    if self._prune_step(con, prune_jobs[0]):
                        prune_jobs.popleft()[2].set()
                    if prune_jobs:
                        continue
            if stopping:
                if not bulk and not precious:
                    break
                if time.monotonic() >= next_retry:
                    continue
                if self._thread_should_give_up():
                    break
                time.sleep(min(0.05, max(0.0, next_retry - time.monotonic())))
            elif (bulk or precious) and self._failing:
                # failing: wait for the retry time but keep taking new rows
                time.sleep(min(0.05, max(0.0, next_retry - time.monotonic())))
        if con is not None:
            try:
                con.execute("PRAGMA wal_checkpoint(PASSIVE)")
            except sqlite3.Error:
                pass
            con.close()

    def _thread_should_give_up(self) -> bool:
        # close() waits with a timeout; the writer keeps retrying until the process ends
        return False

    def _try_connect(self) -> sqlite3.Connection | None:
        try:
            return self._connect_writer()
        except sqlite3.Error as e:
            self._report_failure(f"cannot open the archive for writing: {e}")
            return None

    def _run_hook(self, con: sqlite3.Connection | None) -> None:
        while self._writer_hooks:
            fn, ev, box = self._writer_hooks.popleft()
            try:
                box.append(fn(con))
            except BaseException as e:  # handed back to the caller
                box.append(e)
            ev.set()

    def _enforce_bound(self, bulk: deque, precious: deque) -> None:
        over = len(bulk) + len(precious) - self.max_held_rows
        if over <= 0:
            return
        dropped: dict[str, int] = {}
        while over > 0 and bulk:
            kind, _ = bulk.popleft()
            dropped[kind] = dropped.get(kind, 0) + 1
            over -= 1
        while over > 0 and precious:
            kind, _ = precious.popleft()
            dropped[kind] = dropped.get(kind, 0) + 1
            over -= 1
        n = sum(dropped.values())
        with self._lock:
            for k, v in dropped.items():
                self._dropped[k] = self._dropped.get(k, 0) + v
            self._held_count -= n
            total = sum(self._dropped.values())
        msg = (f"archive memory limit of {self.max_held_rows} held rows reached while "
               f"writes fail: dropped the {n} oldest ({_json(dropped)}); {total} dropped "
               f"in all")
        log.error(msg)
        self._notify(False, msg)

    def _write_held(self, con: sqlite3.Connection, bulk: deque, precious: deque) -> bool:
        items = list(precious) + list(bulk)
        try:
            try:
                counts = self._write_items(con, items)
            except BAD_ITEM as e:  # one refused row: write the batch row by row
                log.warning("archive: a row was refused (%s); writing the batch row by row", e)
                _rollback(con)
                self._chan_ids.clear()  # ids learnt in the rolled-back transaction
                self._layout_ids.clear()
                counts = self._write_items(con, items, careful=True)
        except (sqlite3.Error, OSError) as e:
            _rollback(con)
            self._chan_ids.clear()
            self._layout_ids.clear()
            self._report_failure(f"archive write failed ({e}); {len(items)} rows held in "
                                 f"memory and retried")
            return False
        bulk.clear()
        precious.clear()
        recovered = False
        with self._lock:
            for k, v in counts.items():
                self._written[k] = self._written.get(k, 0) + v
            self._held_count -= len(items)
            if self._failing:
                self._failing = False
                recovered = True
        if recovered:
            msg = f"archive writes recovered; {len(items)} held rows written"
            log.warning(msg)
            self._notify(True, msg)
        return True

    def _report_failure(self, msg: str) -> None:
        first = False
        with self._lock:
            self._failures += 1
            self._last_error = msg
            if not self._failing:
                self._failing = True
                first = True
        if first:
            log.error(msg)
            self._notify(False, msg)
        else:
            log.debug(msg)

    def _notify(self, ok: bool, msg: str) -> None:
        if self.on_status is None:
            return
        try:
            self.on_status(ok, msg)
        except Exception:  # a listener's bug must not stop the writer
            log.exception("archive status listener failed")

    # the actual SQL, inside one transaction
    def _channel_id(self, con: sqlite3.Connection, name: str) -> int:
        cid = self._chan_ids.get(name)
        if cid is None:
            con.execute("INSERT OR IGNORE INTO channel(name) VALUES (?)", (name,))
            cid = con.execute("SELECT id FROM channel WHERE name=?", (name,)).fetchone()[0]
            self._chan_ids[name] = cid
        return cid

    def _layout(self, con: sqlite3.Connection, names: tuple[str, ...]) -> tuple[int, list[int]]:
        got = self._layout_ids.get(names)
        if got is None:
            key = _json(list(names))
            con.execute("INSERT OR IGNORE INTO telemetry_layout(channels) VALUES (?)", (key,))
            lid = con.execute("SELECT id FROM telemetry_layout WHERE channels=?",
                              (key,)).fetchone()[0]
            got = (lid, [self._channel_id(con, n) for n in names])
            self._layout_ids[names] = got
        return got

    def _write_items(self, con: sqlite3.Connection, items: list,
                     careful: bool = False) -> dict[str, int]:
        """Write ``items`` in one transaction. ``careful``: each item in a savepoint of its
        own, and an item SQLite refuses (a bad value, not a bad disk) is dropped, counted
        and logged instead of failing the batch."""
        counts: dict[str, int] = {}
        tel_rows: list[tuple] = []
        by_layout: dict[int, tuple[list[int], list[float], list[bytes]]] = {}
        con.execute("BEGIN IMMEDIATE")
        for kind, a in items:
            if careful:
                con.execute("SAVEPOINT item")
                try:
                    self._write_one(con, kind, a, tel_rows, by_layout, careful)
                except BAD_ITEM as e:
                    con.execute("ROLLBACK TO item")
                    self._chan_ids.clear()  # a channel or layout this row added is gone
                    self._layout_ids.clear()
                    with self._lock:
                        self._dropped[f"bad_{kind}"] = self._dropped.get(f"bad_{kind}", 0) + 1
                    log.error("archive: a %s row was refused and dropped: %s", kind, e)
                    con.execute("RELEASE item")
                    continue
                con.execute("RELEASE item")
            else:
                self._write_one(con, kind, a, tel_rows, by_layout, careful)
            counts[kind] = counts.get(kind, 0) + 1
        if tel_rows:
            con.executemany("INSERT INTO telemetry(t, seq, layout, data, session) "
                            "VALUES (?,?,?,?,?)", tel_rows)
        for cids, ts, blobs in by_layout.values():
            self._upsert_rollups(con, cids, np.asarray(ts),
                                 np.frombuffer(b"".join(blobs), np.float64)
                                 .reshape(len(ts), len(cids)))
        con.execute("COMMIT")
        return counts

    def _write_one(self, con: sqlite3.Connection, kind: str, a: tuple, tel_rows: list,
                   by_layout: dict, careful: bool) -> None:
        *a, sid = a  # the session the row belongs to (stamped by _put)
        if kind == "telemetry":
            t, seq, names, data = a
            lid, cids = self._layout(con, names)
            if careful:  # row by row, so a refused row does not take the others along
                con.execute("INSERT INTO telemetry(t, seq, layout, data, session) "
                            "VALUES (?,?,?,?,?)", (t, seq, lid, data, sid))
            else:
                tel_rows.append((t, seq, lid, data, sid))
            g = by_layout.setdefault(lid, (cids, [], []))
            g[1].append(t)
            g[2].append(data)
        elif kind == "pose":
            con.execute("INSERT INTO pose(t, x, y, theta, session) VALUES (?,?,?,?,?)",
                        (*a, sid))
        elif kind == "event":
            con.execute("INSERT INTO event(t, kind, data, session) VALUES (?,?,?,?)", (*a, sid))
        elif kind == "scan":
            con.execute("INSERT INTO scan(t, angle_min, angle_increment, range_max, ranges, "
                        "session) VALUES (?,?,?,?,?,?)", (*a, sid))
        elif kind == "alarm_transition":
            con.execute(
                "INSERT INTO alarm_transition(t, alarm, source, priority, from_state, "
                "to_state, value, limit_value, unit, text, user, reason, origin, session) "
                "VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?)", (*a, sid))
        elif kind == "command":
            t, user, command, args, seq, acked = a
            con.execute("INSERT INTO command(t, user, command, args, seq, acked, session) "
                        "VALUES (?,?,?,?,?,?,?)",
                        (t, user, command, args, seq,
                         None if acked is None else int(bool(acked)), sid))
        elif kind == "ack":
            seq, ok, reason, t = a
            cur = con.execute(
                "UPDATE command SET acked=?, ack_reason=?, ack_t=? WHERE id = ("
                "SELECT id FROM command WHERE seq=? AND session IS ? ORDER BY id DESC LIMIT 1)",
                (int(ok), reason, t, seq, sid))
            if cur.rowcount == 0:  # an ack for a command we never saw: keep it anyway
                con.execute("INSERT INTO event(t, kind, data, session) VALUES (?,?,?,?)",
                            (t, "command_ack_unmatched",
                             _json({"cmd_seq": seq, "ok": ok, "reason": reason}), sid))
        elif kind == "meter_reading":
            t, point, value, unit, conf, fused, state, error, jpeg = a
            snap = None
            if jpeg:
                snap = con.execute(
                    "INSERT INTO snapshot(t, reason, ref, size, jpeg, session) "
                    "VALUES (?,?,?,?,?,?)", (t, "meter", point, len(jpeg), jpeg, sid)).lastrowid
            con.execute("INSERT INTO meter_reading(t, point, value, unit, confidence, "
                        "fused, state, error, snapshot_id, session) "
                        "VALUES (?,?,?,?,?,?,?,?,?,?)",
                        (t, point, value, unit, conf, int(fused), state, error, snap, sid))
        elif kind == "snapshot":
            t, jpeg, reason, ref = a
            if jpeg:
                con.execute("INSERT INTO snapshot(t, reason, ref, size, jpeg, session) "
                            "VALUES (?,?,?,?,?,?)", (t, reason, ref, len(jpeg), jpeg, sid))
        elif kind == "map":
            con.execute("INSERT INTO map(t, png, session) VALUES (?,?,?)", (*a, sid))
        elif kind == "path":
            con.execute("INSERT INTO path(t, kind, points, session) VALUES (?,?,?,?)",
                        (*a, sid))
        elif kind == "session_robot":
            con.execute("UPDATE session SET robot=? WHERE id=?", (a[1], a[0]))
        elif kind == "session_end":
            con.execute("UPDATE session SET ended_t=? WHERE id=?", (a[1], a[0]))

    def _encode_image(self, kind: str, args: tuple) -> tuple[str, tuple]:
        """An RGB image given for a snapshot becomes a small JPEG here, in the writer
        thread, once (so the GUI thread never encodes)."""
        i = 1 if kind == "snapshot" else 8
        img = args[i]
        if img is None or isinstance(img, bytes):
            return kind, args
        jpeg = small_jpeg(img)
        if jpeg is None:
            with self._lock:
                self._dropped["bad_snapshot"] = self._dropped.get("bad_snapshot", 0) + 1
            log.warning("archive: a %s snapshot is not an RGB image; not stored", kind)
        return kind, (*args[:i], jpeg, *args[i + 1:])

    @staticmethod
    def _upsert_rollups(con: sqlite3.Connection, cids: list[int], t: np.ndarray,
                        v: np.ndarray) -> None:
        order = np.argsort(t, kind="stable")
        t, v = t[order], v[order]
        fin = np.isfinite(v)
        n_all = fin.astype(np.int64)
        s_all = np.where(fin, v, 0.0)
        lo_all = np.where(fin, v, np.inf)
        hi_all = np.where(fin, v, -np.inf)
        rows = []
        for level in ROLLUP_LEVELS_S:
            b = np.floor(t / level).astype(np.int64)
            starts = np.concatenate(([0], np.flatnonzero(np.diff(b)) + 1))
            buckets = b[starts]
            n = np.add.reduceat(n_all, starts, axis=0)
            s = np.add.reduceat(s_all, starts, axis=0)
            lo = np.minimum.reduceat(lo_all, starts, axis=0)
            hi = np.maximum.reduceat(hi_all, starts, axis=0)
            for j, cid in enumerate(cids):
                nz = n[:, j] > 0
                rows.extend(zip([level] * int(nz.sum()), [cid] * int(nz.sum()),
                                buckets[nz].tolist(), n[nz, j].tolist(), s[nz, j].tolist(),
                                lo[nz, j].tolist(), hi[nz, j].tolist(), strict=True))
        con.executemany(
            "INSERT INTO rollup(level, channel, bucket, n, sum, vmin, vmax) "
            "VALUES (?,?,?,?,?,?,?) ON CONFLICT(level, channel, bucket) DO UPDATE SET "
            "n = n + excluded.n, sum = sum + excluded.sum, "
            "vmin = min(vmin, excluded.vmin), vmax = max(vmax, excluded.vmax)", rows)

    # retention
    PRUNE_CHUNK = 5000

    def _prune_step(self, con: sqlite3.Connection, job: list) -> bool:
        """Export (once) and delete one chunk of rows older than the cutoff.
        Returns True when the job is done."""
        cutoff, export_dir = job[0], job[1]
        try:
            if export_dir is not None and len(job) == 3:
                job.append(self._export_old(con, cutoff, Path(export_dir)))
            for table in TIMED_TABLES:
                cur = con.execute(f"DELETE FROM {table} WHERE id IN (SELECT id FROM {table} "
                                  f"WHERE t < ? ORDER BY t LIMIT ?)",
                                  (cutoff, self.PRUNE_CHUNK))
                if cur.rowcount:
                    with self._lock:
                        self._pruned[table] = self._pruned.get(table, 0) + cur.rowcount
                    return False
            channels = [r[0] for r in con.execute("SELECT id FROM channel")]
            for level in ROLLUP_LEVELS_S:
                end = math.floor(cutoff / level)
                for cid in channels:
                    first = con.execute("SELECT min(bucket) FROM rollup WHERE level=? AND "
                                        "channel=?", (level, cid)).fetchone()[0]
                    if first is None or first >= end:
                        continue
                    cur = con.execute(
                        "DELETE FROM rollup WHERE level=? AND channel=? AND bucket < ?",
                        (level, cid, min(end, first + self.PRUNE_CHUNK)))
                    with self._lock:
                        self._pruned["rollup"] = self._pruned.get("rollup", 0) + cur.rowcount
                    return False
        except Exception as e:  # retention must never stop the writer
            self._report_failure(f"archive retention step failed: {e}")
            return True
        return True

    def _export_old(self, con: sqlite3.Connection, cutoff: float, folder: Path) -> list[str]:
        folder.mkdir(parents=True, exist_ok=True)
        stamp = datetime.fromtimestamp(cutoff, UTC).strftime("%Y%m%dT%H%M%SZ")
        written = []
        for table in TIMED_TABLES:
            if con.execute(f"SELECT 1 FROM {table} WHERE t < ? LIMIT 1", (cutoff,)).fetchone() \
                    is None:
                continue
            out = folder / f"{table}-before-{stamp}.csv"
            if table == "telemetry":
                self._export_telemetry(con, None, -math.inf, cutoff, out, upper_open=True)
            else:
                cur = con.execute(f"SELECT * FROM {table} WHERE t < ? ORDER BY t", (cutoff,))
                cols = [d[0] for d in cur.description]
                with open(out, "w", newline="", encoding="utf-8") as f:
                    w = csv.writer(f)
                    w.writerow(["time_utc", *cols])
                    for row in cur:
                        w.writerow([_iso(row[cols.index("t")]),
                                    *(f"<{len(x)} bytes>" if isinstance(x, bytes) else x
                                      for x in row)])
            written.append(str(out))
        with self._lock:
            self._exported.extend(written)
        return written
