"""Background threads yield to the GUI thread: lower the calling thread's priority.

The desk's helpers (the archive's writer, the heap trimmer, the simulated
robot's output pump) do work that may wait some milliseconds; the
GUI thread's event loop may not. When they are runnable at the same time on the
same CPU, the scheduler shares it by weight, so a helper at the GUI thread's
priority can hold the CPU for a whole time slice while a repaint waits.
:func:`lower_this_thread` gives the calling thread a lower priority:

- Linux: a nice value ``step`` above the process's (``setpriority`` on the
  thread's own id: on Linux nice is per thread). Under CFS a thread at nice +10
  has about a tenth of the weight of one at nice 0, so a waking GUI thread runs
  first and a busy helper still gets the CPU whenever the GUI thread is idle;
  no helper can starve, unlike with ``SCHED_IDLE``.
- Windows: ``THREAD_PRIORITY_BELOW_NORMAL`` for the calling thread.
- elsewhere (macOS): nothing is changed.

The meter's job pool (app/gui_jobs.py) keeps its priority: its readings must
keep pace with the patrol's stop at a gauge, and on a loaded machine (the test
suite and two simulations at nice 0) a pool thread at nice +10 read one frame
of a stop where the patrol needed several, and the headless demo's gauges went
unread.

Raising a nice value needs no privilege. It is done once per thread; later
calls on the same thread return at once.
"""

from __future__ import annotations

import logging
import os
import sys
import threading

__all__ = ["BACKGROUND_NICE", "lower_this_thread", "thread_nice"]

log = logging.getLogger(__name__)

BACKGROUND_NICE = 10  # nice steps above the process's own (Linux)
_done = threading.local()


def thread_nice(tid: int | None = None) -> int | None:
    """A thread's nice value (Linux; the calling thread when ``tid`` is None)."""
    if not sys.platform.startswith("linux"):
        return None
    return os.getpriority(os.PRIO_PROCESS, threading.get_native_id() if tid is None else tid)


def lower_this_thread(step: int = BACKGROUND_NICE) -> bool:
    """Lower the calling thread's scheduling priority; True if it was lowered
    (now or by an earlier call on this thread)."""
    if getattr(_done, "lowered", None) is not None:
        return _done.lowered
    lowered = False
    try:
        if sys.platform.startswith("linux"):
            tid = threading.get_native_id()
            now = os.getpriority(os.PRIO_PROCESS, tid)
            os.setpriority(os.PRIO_PROCESS, tid, min(19, now + step))
            lowered = True
        elif sys.platform == "win32":
            import ctypes

            k32 = ctypes.windll.kernel32  # type: ignore[attr-defined]
            lowered = bool(k32.SetThreadPriority(k32.GetCurrentThread(), -1))  # BELOW_NORMAL
    except (OSError, AttributeError) as e:  # a sandbox that forbids it: run as before
        log.debug("thread priority left as it was: %s", e)
    _done.lowered = lowered
    return lowered
