"""Which threads of the process ran while the GUI thread's beat was late.

:class:`GapThreads` is fed by the stall sampler's watchdog thread (``snapshot``
every sample period: each thread's nanoseconds run on a CPU, from
``/proc/self/task/TID/schedstat``, Linux) and by the GUI thread's beat (``late``:
a gap that ended late). A late gap is put on the threads' CPU between the last
snapshot before it began and the first one after it ended, so a thread that held
the GIL (or the CPU) while the GUI thread waited shows with the CPU it ran then.
While the GUI thread is late the watchdog also notes the innermost own-code line
of every other Python thread (``note_stacks``): the line where a thread that held
the GIL through a long C call came back to Python.

Files are opened, read and closed at each snapshot (no handle stays open: the
soak counts the process's handles).
"""

from __future__ import annotations

import collections
import os
import sys
import threading

TASKS = "/proc/self/task"


def _run_ns(tid: str) -> int | None:
    try:
        with open(f"{TASKS}/{tid}/schedstat", "rb") as f:
            return int(f.read().split()[0])
    except (OSError, ValueError, IndexError):
        return None


def _comm(tid: int) -> str:
    try:
        with open(f"{TASKS}/{tid}/comm") as f:
            return f.read().strip()
    except OSError:
        return "?"


class GapThreads:
    """Per-thread CPU over the late gaps of the GUI thread's beat."""

    def __init__(self, attribute_ms: float = 20.0, keep_s: float = 2.0,
                 listed: int = 25) -> None:
        self.attribute_s = attribute_ms / 1000  # late gaps over this are attributed
        self.keep_s = keep_s
        self.listed = listed
        self.main_native = threading.main_thread().native_id
        self._snaps: collections.deque[tuple[float, dict[int, int]]] = collections.deque()
        self._lock = threading.Lock()
        self._pending: list[tuple[float, float, str]] = []  # (start, end, class)
        self.gaps: list[tuple[float, str, float, list[tuple[str, float]], list[str]]] = []
        self.cpu_in_gaps: collections.Counter[str] = collections.Counter()
        self.lines_in_gaps: collections.Counter[str] = collections.Counter()
        self._lines_now: list[str] = []
        self.count = 0

    def name(self, tid: int) -> str:
        for t in threading.enumerate():
            if t.native_id == tid:
                return "GUI" if tid == self.main_native else t.name
        return _comm(tid)

    # -- the watchdog thread ------------------------------------------------
    def snapshot(self, now: float) -> None:
        try:
            tids = os.listdir(TASKS)
        except OSError:
            return
        snap = {}
        for tid in tids:
            ns = _run_ns(tid)
            if ns is not None:
                snap[int(tid)] = ns
        with self._lock:
            self._snaps.append((now, snap))
            while self._snaps and now - self._snaps[0][0] > self.keep_s:
                self._snaps.popleft()
            pending, self._pending = self._pending, []
        for start, end, kind in pending:
            if now < end:
                with self._lock:
                    self._pending.append((start, end, kind))
                continue
            self._attribute(start, end, kind)

    def note_stacks(self, own: tuple[str, ...], where) -> None:
        """The innermost own-code line of each other Python thread, now."""
        names = {t.ident: t.name for t in threading.enumerate()}
        frames = sys._current_frames()
        try:
            for ident, frame in frames.items():
                if ident in (threading.main_thread().ident, threading.get_ident()):
                    continue
                f = frame
                while f is not None and not f.f_code.co_filename.startswith(own):
                    f = f.f_back
                if f is not None:
                    self._lines_now.append(f"{names.get(ident, ident)}: "
                                           f"{where(f.f_code.co_filename)}:{f.f_lineno} "
                                           f"{f.f_code.co_name}")
                f = None
        finally:
            del frames, frame

    # -- the GUI thread -----------------------------------------------------
    def late(self, start: float, end: float, kind: str) -> None:
        """A beat gap [start, end] that ended late; ``kind`` is the ledger's class."""
        with self._lock:
            self._pending.append((start, end, kind))

    # -- inside -------------------------------------------------------------
    def _attribute(self, start: float, end: float, kind: str) -> None:
        with self._lock:
            snaps = list(self._snaps)
            lines, self._lines_now = self._lines_now, []
        before = next((s for t, s in reversed(snaps) if t <= start), None)
        after = next((s for t, s in snaps if t >= end), None)
        if before is None or after is None:
            return
        ran = sorted(((after[tid] - ns) / 1e9, tid) for tid, ns in before.items()
                     if tid in after and after[tid] > ns)[::-1]
        top = [(self.name(tid), s) for s, tid in ran[:4] if s > 0.0005]
        self.count += 1
        for n, s in top:
            self.cpu_in_gaps[n] += s
        for line in set(lines):
            self.lines_in_gaps[line] += 1
        if len(self.gaps) < self.listed:
            self.gaps.append((end - start, kind, end, top, sorted(set(lines))[:4]))

    def report_lines(self, period_s: float) -> list[str]:
        out = [f"late gaps over {self.attribute_s * 1000:.0f} ms put on the threads that ran "
               f"in them: {self.count}; CPU in them by thread: " + (", ".join(
                   f"{n} {1000 * s:.0f} ms" for n, s in self.cpu_in_gaps.most_common(8))
                   or "-")]
        for gap, kind, _end, top, lines in self.gaps:
            out.append(f"  {1000 * (gap - period_s):5.0f} ms late ({kind}): " + ", ".join(
                f"{n} {1000 * s:.1f} ms" for n, s in top))
            for line in lines:
                out.append(f"        other thread at {line}")
        if self.lines_in_gaps:
            out.append("other threads' innermost own-code lines seen in late gaps:")
            for line, n in self.lines_in_gaps.most_common(10):
                out.append(f"  {n:5d}  {line}")
        return out
