"""Where an asyncio loop's stalls come from: its own callbacks running long on the
CPU, the garbage collector, or its thread not being run at all (another thread
holding the GIL, or the operating system giving the CPU to another process).

Three measures, each on one loop's thread:

- :class:`StallWatch` (cheap, always on in the server): a task sleeps ``period_s``
  and notes how late it woke (the loop's stall) and how much CPU the loop's thread
  used meanwhile (``time.thread_time``). A stall with little CPU was not the
  loop's code: its thread was waiting to run.
- :class:`CallbackProbe` (for benches and diagnosis): every callback the loop
  runs (``asyncio.Handle._run``: task steps, timers, ``call_soon`` callbacks) is
  timed in wall and in thread CPU; the longest of each is named (a task by its
  coroutine). A callback long in wall time but short in CPU was descheduled or
  waited for the GIL in the middle.
- :class:`GcProbe`: every garbage collection in the process (``gc.callbacks``),
  its pause and generation; a collection stops every Python thread, the loop's too.

A stall is then told apart as: CPU of the loop's thread during the late window
(our code), CPU of the process's other threads (they held the GIL), collections
inside it (GC, in whichever thread), and window time in which the process did not
run at all (the operating system ran other processes).
"""

from __future__ import annotations

import asyncio
import collections
import gc
import threading
import time
from dataclasses import dataclass, field
from typing import Any

__all__ = ["CallbackProbe", "GcProbe", "Stall", "StallWatch", "full_collection"]


@dataclass
class Stall:
    """One late wake-up of the watching task: ``late_s`` after its ``period_s`` sleep
    (window from ``t0`` to ``t1``, ``time.perf_counter``), while the loop's thread used
    ``cpu_s`` of CPU, the whole process ``proc_s`` (every thread) and collections
    paused every thread for ``gc_s``."""

    late_s: float
    cpu_s: float
    t0: float
    t1: float
    proc_s: float = 0.0
    gc_s: float = 0.0

    @property
    def others_s(self) -> float:
        """CPU the process's other threads used in the window: while one of them holds
        the GIL, the loop's thread cannot run."""
        return max(0.0, self.proc_s - self.cpu_s)

    @property
    def unscheduled_s(self) -> float:
        """Window time in which no thread of the process ran: the operating system
        gave the CPUs to other processes (``window - process CPU``; on a machine with
        idle cores two busy threads could make it negative, hence floored at 0)."""
        return max(0.0, self.t1 - self.t0 - self.proc_s)


@dataclass
class StallWatch:
    """The loop's stalls, measured by a task that sleeps ``period_s`` again and again
    (:meth:`run`, on the watched loop). ``over_s``: the stall counted as one."""

    period_s: float = 0.05
    over_s: float = 0.05
    worst: Stall | None = None
    over: int = 0
    windows: int = 0
    gc_probe: GcProbe | None = None
    recent: collections.deque = field(default_factory=lambda: collections.deque(maxlen=50))

    @property
    def max_stall_s(self) -> float:
        return 0.0 if self.worst is None else self.worst.late_s

    def reset(self) -> None:
        self.worst, self.over, self.windows = None, 0, 0
        self.recent.clear()

    async def run(self) -> None:
        while True:
            t0, c0, p0 = time.perf_counter(), time.thread_time(), time.process_time()
            await asyncio.sleep(self.period_s)
            self.note(t0, c0, time.perf_counter(), time.thread_time(),
                      time.process_time() - p0)

    def note(self, t0: float, c0: float, t1: float, c1: float, proc_s: float = 0.0
             ) -> Stall | None:
        """One window: slept at ``t0`` (thread CPU ``c0``), woke at ``t1`` (``c1``);
        the process used ``proc_s`` of CPU meanwhile."""
        self.windows += 1
        late = t1 - t0 - self.period_s
        if late <= self.over_s and (self.worst is not None and late <= self.worst.late_s):
            return None
        s = Stall(late, c1 - c0, t0, t1, proc_s)
        if self.gc_probe is not None:
            s.gc_s = self.gc_probe.paused_between(t0, t1)
        if late > self.over_s:
            self.over += 1
            self.recent.append(s)
        if self.worst is None or late > self.worst.late_s:
            self.worst = s
        return s


class GcProbe:
    """Garbage collections in the process: count and pause by generation, the longest,
    and the recent pauses (to find those inside a stall's window)."""

    def __init__(self, keep: int = 2000) -> None:
        self.count = [0, 0, 0]
        self.total_s = [0.0, 0.0, 0.0]
        self.max_s = [0.0, 0.0, 0.0]
        self.pauses: collections.deque = collections.deque(maxlen=keep)  # (t0, t1, gen)
        self._t0 = 0.0
        self._on = False

    def __enter__(self) -> GcProbe:
        if not self._on:
            gc.callbacks.append(self._cb)
            self._on = True
        return self

    def __exit__(self, *exc: Any) -> None:
        if self._on:
            gc.callbacks.remove(self._cb)
            self._on = False

    def _cb(self, phase: str, info: dict) -> None:
        now = time.perf_counter()
        if phase == "start":
            self._t0 = now
            return
        gen = int(info.get("generation", 2))
        d = now - self._t0
        self.count[gen] += 1
        self.total_s[gen] += d
        self.max_s[gen] = max(self.max_s[gen], d)
        self.pauses.append((self._t0, now, gen))

    def paused_between(self, t0: float, t1: float) -> float:
        """Seconds of collection between ``t0`` and ``t1`` (``time.perf_counter``)."""
        return sum(max(0.0, min(b, t1) - max(a, t0)) for a, b, _ in list(self.pauses)
                   if b > t0 and a < t1)


def _callback_name(cb: Any) -> str:
    """A task's step by the task's coroutine, any other callback by its qualified name."""
    owner = getattr(cb, "__self__", None)
    if isinstance(owner, asyncio.Task):
        coro = owner.get_coro()
        return "task " + getattr(coro, "__qualname__", type(coro).__name__)
    return getattr(cb, "__qualname__", None) or repr(cb)


class CallbackProbe:
    """Times every callback run on one thread's asyncio loop (wall and thread CPU).

    Install with :meth:`install` from the loop's thread; :meth:`uninstall` to stop.
    It wraps ``asyncio.Handle._run`` for the whole process (other threads' loops pass
    through with one dictionary look-up); only one probe a thread."""

    _probes: dict[int, CallbackProbe] = {}
    _orig_run: Any = None
    _lock = threading.Lock()

    def __init__(self, over_s: float = 0.05) -> None:
        self.over_s = over_s
        self.thread_id: int | None = None
        self.reset()

    def reset(self) -> None:
        self.n = 0
        self.cpu_total_s = 0.0
        self.max_cpu_s, self.max_cpu_name = 0.0, ""
        self.max_wall_s, self.max_wall_cpu_s, self.max_wall_name = 0.0, 0.0, ""
        self.over_cpu = self.over_wall = 0
        self.by_name_cpu: dict[str, float] = collections.defaultdict(float)
        self.all_by_name: dict[str, list] = {}  # name -> [count, CPU s] (picklable)

    def install(self) -> CallbackProbe:
        cls = CallbackProbe
        with cls._lock:
            self.thread_id = threading.get_ident()
            cls._probes[self.thread_id] = self
            if cls._orig_run is None:
                cls._orig_run = asyncio.Handle._run
                asyncio.Handle._run = _timed_run
        return self

    def uninstall(self) -> None:
        cls = CallbackProbe
        with cls._lock:
            cls._probes.pop(self.thread_id, None)
            if not cls._probes and cls._orig_run is not None:
                asyncio.Handle._run = cls._orig_run
                cls._orig_run = None

    def note(self, cb: Any, wall_s: float, cpu_s: float) -> None:
        self.n += 1
        self.cpu_total_s += cpu_s
        name = _callback_name(cb)  # count and CPU of every callback so named
        every = self.all_by_name.get(name)
        if every is None:
            every = self.all_by_name[name] = [0, 0.0]
        every[0] += 1
        every[1] += cpu_s
        if cpu_s > self.over_s:
            self.over_cpu += 1
        if wall_s > self.over_s:
            self.over_wall += 1
        if cpu_s > 0.005 or wall_s > self.max_wall_s:  # name only what may matter
            name = _callback_name(cb)
            if cpu_s > 0.005:
                self.by_name_cpu[name] += cpu_s
            if cpu_s > self.max_cpu_s:
                self.max_cpu_s, self.max_cpu_name = cpu_s, name
            if wall_s > self.max_wall_s:
                self.max_wall_s, self.max_wall_cpu_s, self.max_wall_name = wall_s, cpu_s, name


def _timed_run(handle: asyncio.Handle) -> None:
    probe = CallbackProbe._probes.get(threading.get_ident())
    if probe is None:
        return CallbackProbe._orig_run(handle)
    cb = handle._callback
    w0, c0 = time.perf_counter(), time.thread_time()
    try:
        return CallbackProbe._orig_run(handle)
    finally:
        probe.note(cb, time.perf_counter() - w0, time.thread_time() - c0)


def full_collection() -> str:
    """A full collection now, timed: the pause a natural generation-2 collection makes
    (it stops every thread of the process, the server's loop too), and what it had to
    walk."""
    tracked = len(gc.get_objects())
    c0, w0 = time.thread_time(), time.perf_counter()
    gc.collect()
    cpu, w = time.thread_time() - c0, time.perf_counter() - w0
    return (f"a full collection now: {cpu * 1000:.1f} ms CPU ({w * 1000:.1f} ms wall), "
            f"{tracked} objects tracked, {gc.get_freeze_count()} frozen out of it")
