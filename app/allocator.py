"""Keep a long-running desk's memory from creeping under glibc's allocator (Linux).

The desk allocates many large, short-lived buffers: every camera frame is decoded
into a 0.9 MB array on the link thread and let go on the GUI thread, a dozen times
a second. glibc serves a block that large with its own memory mapping, returned to
the system when freed, but it raises that threshold to the size of each such block
freed (its "dynamic mmap threshold"): after the first frame, frames come from the
threads' heaps, where freed blocks are kept and fragment: after ten minutes of a
desk soak, 11 MB of its resident memory was such kept memory (``malloc_trim`` gave
it back).

:func:`settle_allocator` fixes the threshold (``mallopt(M_MMAP_THRESHOLD)``, which
also turns the dynamic adjustment off), so large buffers keep their own mappings
and go back to the system when freed. Elsewhere (macOS, Windows, musl) it does
nothing; an operator's ``MALLOC_MMAP_THRESHOLD_`` setting is left as it is.

Smaller blocks still come from the heaps, and a burst (a backlog of messages after
the window was busy, a patrol's first meter readings on the pool thread) leaves
free holes inside them that glibc keeps: only the top of a heap is given back by
itself. :func:`start_heap_trimmer` runs a thread that calls ``malloc_trim(0)``
once a minute, which hands the free pages inside every heap back to the system,
so resident memory follows what is in use instead of the highest it ever was.
The call runs without Python's lock (ctypes releases it) and off the GUI thread.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import logging
import os
import sys
import threading
import time

from app.core.thread_priority import lower_this_thread

log = logging.getLogger(__name__)

__all__ = ["MMAP_THRESHOLD_BYTES", "TRIM_PERIOD_S", "HeapTrimmer", "settle_allocator",
           "start_heap_trimmer"]

M_MMAP_THRESHOLD = -3  # glibc's mallopt parameter number
MMAP_THRESHOLD_BYTES = 128 * 1024  # glibc's own starting value
TRIM_PERIOD_S = 60.0


def _glibc():
    if not sys.platform.startswith("linux"):
        return None
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        libc.gnu_get_libc_version  # noqa: B018 - glibc only: musl has no such function
        return libc
    except (OSError, AttributeError):
        return None


def settle_allocator(threshold_bytes: int = MMAP_THRESHOLD_BYTES) -> bool:
    """Fix glibc's mmap threshold at ``threshold_bytes``; True when it was set."""
    if "MALLOC_MMAP_THRESHOLD_" in os.environ:
        return False  # the operator chose it
    libc = _glibc()
    if libc is None:
        return False
    ok = bool(libc.mallopt(M_MMAP_THRESHOLD, int(threshold_bytes)))
    if ok:
        log.debug("allocator: blocks from %d bytes get their own mapping", threshold_bytes)
    else:
        log.warning("allocator: mallopt(M_MMAP_THRESHOLD, %d) refused", threshold_bytes)
    return ok


class HeapTrimmer:
    """A daemon thread calling glibc's ``malloc_trim(0)`` every ``period_s`` seconds.
    ``trims`` counts the calls, ``longest_s`` is the longest one took."""

    def __init__(self, libc, period_s: float = TRIM_PERIOD_S) -> None:
        if period_s <= 0:
            raise ValueError(f"period_s must be positive, got {period_s}")
        self._trim = libc.malloc_trim
        self.period_s = float(period_s)
        self.trims = 0
        self.longest_s = 0.0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="heap-trimmer", daemon=True)

    def start(self) -> HeapTrimmer:
        self._thread.start()
        return self

    def trim(self) -> None:
        t0 = time.perf_counter()
        self._trim(0)
        self.longest_s = max(self.longest_s, time.perf_counter() - t0)
        self.trims += 1

    def _run(self) -> None:
        lower_this_thread()  # a trim can wait; the GUI thread cannot
        while not self._stop.wait(self.period_s):
            self.trim()

    def stop(self, timeout: float = 5.0) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout)


_trimmer: HeapTrimmer | None = None


def start_heap_trimmer(period_s: float = TRIM_PERIOD_S) -> HeapTrimmer | None:
    """The process's heap trimmer, started on the first call (None off glibc)."""
    global _trimmer
    if _trimmer is None:
        libc = _glibc()
        if libc is None or not hasattr(libc, "malloc_trim"):
            return None
        _trimmer = HeapTrimmer(libc, period_s).start()
        log.debug("allocator: free heap pages given back every %g s", period_s)
    return _trimmer
