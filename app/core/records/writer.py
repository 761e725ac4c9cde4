"""The archive's writer thread: gathers queued rows, writes them in batches,
holds and retries them while writes fail, and runs retention between batches.

Mixed into :class:`app.core.records.archive.Archive` (see its module docstring for
the failure and memory rules); nothing here imports Qt.
"""

from __future__ import annotations

import logging
import queue
import sqlite3
import threading
import time
from collections import deque

from app.core.records.rows import BAD_ITEM, _json
from app.core.thread_priority import lower_this_thread

log = logging.getLogger("app.core.records.archive")  # the archive's one logger

BULK_KINDS = frozenset({"telemetry", "pose"})
_STOP = object()


def _rollback(con: sqlite3.Connection) -> None:
    try:
        con.execute("ROLLBACK")
    except sqlite3.Error:
        pass


class ArchiveWriter:
    """The writer thread's loop, connection, hooks, memory bound and failure reports."""

    def _connect_writer(self) -> sqlite3.Connection:
        con = sqlite3.connect(self.path, timeout=self.busy_timeout_ms / 1000.0,
                              isolation_level=None, check_same_thread=False)
        con.execute(f"PRAGMA busy_timeout={int(self.busy_timeout_ms)}")
        con.execute("PRAGMA journal_mode=WAL")
        con.execute("PRAGMA synchronous=NORMAL")
        return con

    def _writer_main(self) -> None:
        lower_this_thread()  # the GUI thread's repaints go first
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
