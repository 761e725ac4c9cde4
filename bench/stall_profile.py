"""Where the desk's GUI thread stalls: a watchdog that samples its Python stack.

A QTimer on the GUI thread beats every ``period_ms``; a watchdog thread checks the
beat every ``sample_ms``. When the beat is later than ``period_ms + threshold_ms``
the GUI thread is stalled, and while it stays so the watchdog records the GUI
thread's Python stack (``sys._current_frames()``) every ``sample_ms``. Each sample
stands for the time since the previous one, so the report gives stalled time by:

- the whole stack (outermost frames cut to the last ``depth``), most time first;
- the innermost frame of the project's own code (app/, sim_robot/, bench/), which
  is usually the line to fix;
- the last Qt event the application delivered before the stall's sample (with
  ``events=True``: an event filter on the QApplication), for stalls inside Qt's own
  C++ (painting, layout), where the Python stack ends at ``app.exec()``.

The watchdog needs the GIL to sample, so a stall inside C code that holds the GIL
shows up as one long sample of the stack where that call returned to Python.

Own work or machine load: at every beat the GUI thread reads its own scheduler
account (``/proc/thread-self/schedstat``, Linux: nanoseconds run on a CPU and
nanoseconds waited in the run queue), so each gap between two beats splits into
the GUI thread's own CPU, its run-queue wait (runnable, but the machine ran
something else: load) and the rest (asleep: the event loop's idle wait, the GIL
held by another thread of the process, a blocking call). A late gap (over
``threshold_ms`` past its period) is put in one class:

- ``own``: the GUI thread itself ran more than ``threshold_ms`` of CPU inside the
  gap; it would be late on an idle machine too, and only code can fix it;
- ``load``: not ``own``, and run-queue wait is the largest part of the lateness;
- ``blocked``: not ``own``, and sleeping (GIL, I/O) is the largest part.

What an asleep GUI thread waits in: while a gap is late the watchdog also reads the
GUI thread's system call (``/proc/self/task/TID/syscall``, Linux). Asleep in the
event loop's poll, it had nothing to do and the kernel woke it late (the machine
did not run the process: a host's pause, which the guest's run-queue account does
not see); asleep in a futex, it waited for the GIL or a lock held by another
thread; in read, write or fsync, a blocking call. The machine's steal time
(``/proc/stat``: time a virtual machine's CPUs were ready but the host ran
something else) over each late gap is also kept.

For ``own`` gaps the watchdog's stack samples taken inside them are kept apart
(``own_by_line``), so the lines that really stalled are not mixed with load.

Used by ``bench/desk_soak.py --stalls``; by itself:

    sampler = StallSampler(); sampler.start()      # on the GUI thread, app running
    ...
    print(sampler.report())
"""

from __future__ import annotations

import collections
import gc
import os
import platform
import sys
import threading
import time

try:
    from bench.gap_threads import GapThreads
except ImportError:  # run from bench/ itself
    from gap_threads import GapThreads

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OWN = tuple(os.path.join(ROOT, d) + os.sep for d in ("app", "sim_robot", "bench"))

Frame = tuple[str, int, str]  # file (relative where ours), line, function


def _where(filename: str) -> str:
    if filename.startswith(ROOT + os.sep):
        return os.path.relpath(filename, ROOT)
    for marker in ("site-packages" + os.sep, "lib" + os.sep + "python"):
        i = filename.find(marker)
        if i >= 0:
            return filename[i + len(marker):] if marker.startswith("site") else \
                "py:" + os.path.basename(filename)
    return filename


def thread_cpu() -> dict[str, float]:
    """CPU seconds of each thread of this process by "name#tid" (Linux /proc)."""
    out: dict[str, float] = {}
    tick = 1.0 / (os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100)
    try:
        tids = os.listdir("/proc/self/task")
    except OSError:
        return out
    for tid in tids:
        try:
            with open(f"/proc/self/task/{tid}/stat") as f:
                head, rest = f.read().rsplit(")", 1)
            fields = rest.split()
            out[f"{head.split('(', 1)[1]}#{tid}"] = (int(fields[11]) + int(fields[12])) * tick
        except (OSError, IndexError, ValueError):
            continue
    return out


# system call numbers of the waits that matter here, by machine (Linux)
_SYSCALLS = {
    "x86_64": {0: "read", 1: "write", 7: "poll", 271: "ppoll", 232: "epoll_wait",
               281: "epoll_pwait", 441: "epoll_pwait2", 202: "futex", 74: "fsync",
               75: "fdatasync", 35: "nanosleep", 230: "clock_nanosleep", 23: "select",
               270: "pselect6", 2: "open", 257: "openat", 3: "close", 4: "stat",
               262: "newfstatat", 44: "sendto", 45: "recvfrom", 46: "sendmsg",
               47: "recvmsg"},
    "aarch64": {63: "read", 64: "write", 73: "ppoll", 22: "epoll_pwait", 98: "futex",
                82: "fsync", 83: "fdatasync", 101: "nanosleep", 115: "clock_nanosleep",
                72: "pselect6", 56: "openat", 57: "close", 79: "newfstatat",
                206: "sendto", 207: "recvfrom", 211: "sendmsg", 212: "recvmsg"},
}.get(platform.machine(), {})
WAIT_KIND = {"poll": "event loop", "ppoll": "event loop", "epoll_wait": "event loop",
             "epoll_pwait": "event loop", "epoll_pwait2": "event loop",
             "select": "event loop", "pselect6": "event loop", "futex": "GIL or lock"}


def syscall_of(tid: int) -> str:
    """What thread ``tid`` of this process is doing: "running", a system call's name
    (or "sys N"), or "?" when it cannot be read."""
    try:
        with open(f"/proc/self/task/{tid}/syscall") as f:
            head = f.read().split(maxsplit=1)
    except OSError:
        return "?"
    if not head:
        return "?"
    if head[0] == "running":
        return "running"
    try:
        n = int(head[0])
    except ValueError:
        return head[0]
    return _SYSCALLS.get(n, f"sys {n}")


def steal_s() -> float | None:
    """Seconds the machine's CPUs were stolen by the host so far (/proc/stat)."""
    try:
        with open("/proc/stat") as f:
            fields = f.readline().split()
        tick = os.sysconf("SC_CLK_TCK")
        return int(fields[8]) / tick
    except (OSError, IndexError, ValueError, AttributeError):
        return None


def stack_of(frame) -> list[Frame]:
    """Outermost first."""
    out: list[Frame] = []
    while frame is not None:
        code = frame.f_code
        out.append((code.co_filename, frame.f_lineno, code.co_name))
        frame = frame.f_back
    out.reverse()
    return out


class StallSampler:
    """Samples the GUI thread's stack while its beat timer is late."""

    def __init__(self, period_ms: int = 20, threshold_ms: float = 50.0,
                 sample_ms: float = 10.0, depth: int = 12, events: bool = True,
                 sampler_cpus: set[int] | None = None) -> None:
        self.period_s = period_ms / 1000
        self.threshold_s = threshold_ms / 1000
        self.sample_s = sample_ms / 1000
        self.depth = depth
        self.events = events
        self.sampler_cpus = sampler_cpus  # the sampler's own CPUs (Linux): off the GUI's
        self.main_id = threading.main_thread().ident
        self.by_stack: collections.Counter[tuple[Frame, ...]] = collections.Counter()
        self.by_own: collections.Counter[str] = collections.Counter()
        self.by_event: collections.Counter[str] = collections.Counter()
        # the GUI thread's CPU time by innermost own-code line (all the time, stalled
        # or not), from its CPU clock in /proc (Linux; elsewhere nothing is counted)
        self.cpu_by_own: collections.Counter[str] = collections.Counter()
        self.cpu_s = 0.0
        self._t_reset = time.perf_counter()
        self._stat = f"/proc/self/task/{threading.main_thread().native_id}/stat"
        self._tick_s = 1.0 / (os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100)
        self.stalls = 0          # separate stalls seen (the beat late, then on time again)
        self.stalled_s = 0.0     # total sampled stall time
        self.last_event = "-"
        self._beat = time.perf_counter()
        # garbage collections (any thread): count, total and longest time per generation
        self.gc_count = [0, 0, 0]
        self.gc_s = [0.0, 0.0, 0.0]
        self.gc_max_s = [0.0, 0.0, 0.0]
        self.gc_pauses: list[tuple[int, float]] = []  # (generation, seconds), each one
        self._gc_t0 = 0.0
        self._gc_in_gap = 0.0     # GUI-thread collection time since the last beat
        self.own_gc = 0           # own-work late gaps that a collection took most of
        self._threads0 = thread_cpu()
        self.ledger = BeatLedger(self.period_s, self.threshold_s)
        self.gap_threads = GapThreads()
        self.own_by_line: collections.Counter[str] = collections.Counter()
        self._pending: list[tuple[float, str]] = []  # (time, key) sampled since the beat
        self._gui_tid = threading.main_thread().native_id
        self._calls: list[str] = []  # the GUI thread's system calls sampled in a late gap
        # late asleep ("blocked") gaps by what the GUI thread was seen waiting in
        self.blocked_in: collections.Counter[str] = collections.Counter()
        self.blocked_gaps: list[tuple[float, float, str]] = []  # (late s, steal s, calls)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._timer = None
        self._filter = None

    # -- the GUI side ---------------------------------------------------------
    def start(self) -> StallSampler:
        from PySide6.QtCore import QCoreApplication, QObject, Qt, QTimer

        self._timer = QTimer()
        self._timer.setTimerType(Qt.TimerType.PreciseTimer)
        self._timer.timeout.connect(self._on_beat)
        self._timer.start(int(self.period_s * 1000))
        if self.events:
            sampler = self

            class _LastEvent(QObject):
                def eventFilter(self, obj, ev):  # noqa: N802 - Qt's name
                    sampler.last_event = f"{ev.type().name} -> {type(obj).__name__}"
                    return False

            self._filter = _LastEvent()
            QCoreApplication.instance().installEventFilter(self._filter)
        gc.callbacks.append(self._on_gc)
        self._beat = time.perf_counter()
        self._thread = threading.Thread(target=self._watch, name="stall-sampler",
                                        daemon=True)
        self._thread.start()
        return self

    def _on_gc(self, phase: str, info: dict) -> None:
        if phase == "start":
            self._gc_t0 = time.perf_counter()
            return
        g = min(int(info.get("generation", 0)), 2)
        dt = time.perf_counter() - self._gc_t0
        self.gc_count[g] += 1
        self.gc_s[g] += dt
        self.gc_max_s[g] = max(self.gc_max_s[g], dt)
        self.gc_pauses.append((g, dt))
        if threading.get_ident() == self.main_id:
            self._gc_in_gap += dt

    def _on_beat(self) -> None:
        now = time.perf_counter()
        kind = self.ledger.beat(now)
        if now - self._beat - self.period_s > self.gap_threads.attribute_s:
            self.gap_threads.late(self._beat, now, kind or "under threshold")
        pending, self._pending = self._pending, []
        calls, self._calls = self._calls, []
        if kind == "blocked":
            self._note_blocked(calls, now - self._beat - self.period_s)
        in_gc, self._gc_in_gap = self._gc_in_gap, 0.0
        if kind == "own" and in_gc > self.threshold_s / 2:
            self.own_gc += 1
        if kind == "own":
            for _t, key in pending:
                self.own_by_line[key] += self.sample_s
        self._beat = now

    def _note_blocked(self, calls: list[str], late_s: float) -> None:
        """A late gap with the GUI thread asleep: what it was seen waiting in (the
        watchdog's samples; none when the gap was too short to be sampled)."""
        seen = sorted(set(calls)) or ["not sampled"]
        key = " + ".join(f"{c} ({WAIT_KIND[c]})" if c in WAIT_KIND else c for c in seen)
        self.blocked_in[key] += 1
        if len(self.blocked_gaps) < 200:
            self.blocked_gaps.append((late_s, self.ledger.last_steal_s, ", ".join(calls)))

    def reset(self) -> None:
        self.gap_threads = GapThreads()
        self.blocked_in.clear()
        self.blocked_gaps = []
        self.by_stack.clear()
        self.by_own.clear()
        self.by_event.clear()
        self.stalls = 0
        self.stalled_s = 0.0
        self.cpu_by_own.clear()
        self.cpu_s = 0.0
        self.ledger.reset()
        self.own_by_line.clear()
        self._t_reset = time.perf_counter()
        self.gc_count, self.gc_s, self.gc_max_s = [0, 0, 0], [0.0] * 3, [0.0] * 3
        self.gc_pauses = []
        self.own_gc = 0
        self._threads0 = thread_cpu()

    def _gui_cpu_s(self) -> float | None:
        try:
            with open(self._stat) as f:
                fields = f.read().rsplit(")", 1)[1].split()
            return (int(fields[11]) + int(fields[12])) * self._tick_s  # utime + stime
        except (OSError, IndexError, ValueError):
            return None

    def stop(self) -> None:
        self._stop.set()
        if self._on_gc in gc.callbacks:
            gc.callbacks.remove(self._on_gc)
        if self._thread is not None:
            self._thread.join(1.0)
        if self._timer is not None:
            self._timer.stop()
        if self._filter is not None:
            from PySide6.QtCore import QCoreApplication

            QCoreApplication.instance().removeEventFilter(self._filter)

    # -- the watchdog ---------------------------------------------------------
    def _watch(self) -> None:
        if self.sampler_cpus:  # so that its sampling takes no time from the GUI thread
            os.sched_setaffinity(0, self.sampler_cpus)
        late_after = self.period_s + self.threshold_s
        in_stall = False
        last = time.perf_counter()
        cpu_last = self._gui_cpu_s()
        while not self._stop.wait(self.sample_s):
            now = time.perf_counter()
            dt, last = now - last, now
            cpu = self._gui_cpu_s()
            if cpu is not None and cpu_last is not None and cpu > cpu_last:
                self._record_cpu(cpu - cpu_last)
            cpu_last = cpu
            self.gap_threads.snapshot(now)
            if now - self._beat > self.period_s + self.gap_threads.attribute_s:
                self.gap_threads.note_stacks(OWN, _where)
                self._calls.append(syscall_of(self._gui_tid))
            if now - self._beat <= late_after:
                in_stall = False
                continue
            stack = self._gui_stack()
            if not stack:
                continue
            if not in_stall:
                in_stall = True
                self.stalls += 1
                dt = now - self._beat - self.period_s  # the stall so far
            self._record(stack, dt)

    def _gui_stack(self) -> list[Frame]:
        """The GUI thread's stack as plain tuples. No frame object outlives this call:
        a frame kept alive keeps its locals alive, and a QPainter left alive past its
        paintEvent makes Qt complain (and paint wrongly)."""
        frame = sys._current_frames().get(self.main_id)
        try:
            return stack_of(frame)
        finally:
            del frame

    def _record_cpu(self, used_s: float) -> None:
        """The GUI thread used ``used_s`` of CPU since the last look: put it on what
        it runs now (a statistical profile: clock ticks are 10 ms).

        The desk's handlers mostly take well under a millisecond, and the thread
        is idle most of the time, so the CPU that a look finds was often spent by
        a handler that has returned: it is put on the idle event loop, keyed by
        the last event delivered ("idle or in Qt, after: ..."). Such a key says
        what ran last, not what cost the time (the last widget a repaint paints
        collects the CPU of the whole repaint and of handlers before it); for the
        cost of each event, ``bench/desk_replay_ab.py --play TAPE --events``."""
        stack = self._gui_stack()
        self.cpu_s += used_s
        self.cpu_by_own[self._key(stack)] += used_s

    def _key(self, stack: list[Frame]) -> str:
        """The innermost own-code line, and the innermost library function below it;
        with no Python below the event loop, the Qt event being handled."""
        if not stack:
            return "-"
        i = next((i for i in range(len(stack) - 1, -1, -1) if stack[i][0].startswith(OWN)),
                 None)
        if i is None:
            return f"{_where(stack[-1][0])}:{stack[-1][1]} {stack[-1][2]}"
        f, n, name = stack[i]
        key = f"{_where(f)}:{n} {name}"
        if i == len(stack) - 1:
            return key + (f"  (idle or in Qt, after: {self.last_event})"
                          if i == 0 or name == "main" else "")
        lf, ln, lname = stack[-1]
        return f"{key} -> {_where(lf)}:{ln} {lname}"

    def _record(self, stack: list[Frame], dt: float) -> None:
        self.stalled_s += dt
        key = self._key(stack)
        self.by_stack[tuple(stack[-self.depth:])] += dt
        self.by_own[key] += dt
        self.by_event[self.last_event] += dt
        self._pending.append((time.perf_counter(), key))

    # -- the report -----------------------------------------------------------
    def gc_pause_lines(self) -> list[str]:
        """Each generation's collection pauses: percentiles and how many over 10, 20
        and 50 ms; and the own-work late gaps that a collection took half of."""
        out = []
        for g in range(3):
            ms = sorted(1000 * dt for gen, dt in self.gc_pauses if gen == g)
            if not ms:
                continue

            def q(p: float, ms=ms) -> float:
                return ms[min(len(ms) - 1, int(p * len(ms)))]

            out.append(f"  gen{g} pauses: {len(ms)}, median {q(0.5):.1f} ms, p90 {q(0.9):.1f}"
                       f", p99 {q(0.99):.1f}, max {ms[-1]:.1f}; over 10/20/50 ms: "
                       f"{sum(v > 10 for v in ms)}/{sum(v > 20 for v in ms)}/"
                       f"{sum(v > 50 for v in ms)}")
        out.append(f"  own-work late gaps with over {self.threshold_s * 500:.0f} ms of "
                   f"collection in them: {self.own_gc}")
        return out

    def report(self, top: int = 12) -> str:
        lines = [f"== stall profile: {self.stalls} stalls over "
                 f"{self.threshold_s * 1000:.0f} ms, {self.stalled_s:.1f} s sampled =="]
        lines += self.ledger.report_lines()
        lines += self.gap_threads.report_lines(self.period_s)
        if self.blocked_in:
            lines.append("late gaps with the GUI thread asleep, by the system calls it was "
                         "seen in (event loop: it had nothing to run and was woken late; "
                         "GIL or lock: another thread held it):")
            for key, n in self.blocked_in.most_common(top):
                lines.append(f"  {n:5d}  {key}")
            lines.append("  each (ms late, ms of the machine's CPU stolen by the host in the "
                         "gap, calls sampled): " + "; ".join(
                             f"{1000 * late:.0f}, {1000 * st:.0f}, [{calls}]"
                             for late, st, calls in self.blocked_gaps[:40]))
        if self.own_by_line:
            lines.append("innermost own-code line inside the gaps of the GUI thread's own work:")
            for key, v in self.own_by_line.most_common(top):
                lines.append(f"  {v:7.2f} s  {key}")
        if not self.stalled_s:
            self.stalled_s = 1e-9  # the CPU lines below still print

        def pct(v: float) -> str:
            return f"{v:7.2f} s {100 * v / self.stalled_s:5.1f} %"

        lines.append("innermost own-code line while stalled:")
        for key, v in self.by_own.most_common(top):
            lines.append(f"  {pct(v)}  {key}")
        lines.append("last Qt event delivered before the sample:")
        for ev, v in self.by_event.most_common(top):
            lines.append(f"  {pct(v)}  {ev}")
        wall = time.perf_counter() - self._t_reset
        if self.cpu_s:
            lines.append(f"GUI thread CPU: {self.cpu_s:.1f} s in {wall:.0f} s "
                         f"({100 * self.cpu_s / wall:.1f} % of a core), by innermost "
                         "own-code line:")
            for key, v in self.cpu_by_own.most_common(top):
                lines.append(f"  {v:7.2f} s {100 * v / self.cpu_s:5.1f} %  {key}")
        lines.append("garbage collections (count, total, longest) by generation: " + "; ".join(
            f"gen{g} {self.gc_count[g]}, {self.gc_s[g] * 1000:.0f} ms, "
            f"{self.gc_max_s[g] * 1000:.1f} ms" for g in range(3)))
        lines += self.gc_pause_lines()
        now = thread_cpu()
        used = sorted(((v - self._threads0.get(k, 0.0), k) for k, v in now.items()),
                      reverse=True)
        lines.append("CPU by thread of this process: " + ", ".join(
            f"{k} {v:.1f} s" for v, k in used[:8] if v > 0.05))
        lines.append("whole stacks (innermost last):")
        for stack, v in self.by_stack.most_common(top):
            lines.append(f"  {pct(v)}")
            for f, n, name in stack:
                lines.append(f"      {_where(f)}:{n} {name}")
        return "\n".join(lines)


def _schedstat(path: str = "/proc/thread-self/schedstat") -> tuple[int, int] | None:
    """(ns run on a CPU, ns waited runnable in the run queue) of the calling thread."""
    try:
        with open(path) as f:
            run, wait = f.read().split()[:2]
        return int(run), int(wait)
    except (OSError, ValueError):
        return None


class BeatLedger:
    """Each gap between two beats of the GUI thread's timer, split into the GUI
    thread's own CPU, its run-queue wait and the rest; :meth:`beat` is called on the
    GUI thread at each beat (it reads the calling thread's account)."""

    KINDS = ("own", "load", "blocked")
    STEP_MS = (10, 15, 20)

    def __init__(self, period_s: float, threshold_s: float) -> None:
        self.period_s = period_s
        self.threshold_s = threshold_s
        self.available = _schedstat() is not None
        self.reset()

    def reset(self) -> None:
        self.t0 = time.perf_counter()
        self._last: tuple[float, int, int] | None = None
        self.gaps = 0
        self.cpu_s = 0.0        # the GUI thread's CPU over all gaps
        self.wait_s = 0.0       # its run-queue wait over all gaps
        self.longest_cpu_s = 0.0  # the most CPU in one gap (the longest step)
        # gaps with more GUI-thread CPU than each of these (ms): long steps, counted
        self.steps_over = dict.fromkeys(self.STEP_MS, 0)
        self.late = {k: 0 for k in self.KINDS}
        self.late_max_s = {k: 0.0 for k in self.KINDS}  # the longest lateness of each kind
        self.late_cpu_s = {k: 0.0 for k in self.KINDS}
        self.late_cpu_max_s = {k: 0.0 for k in self.KINDS}  # the most own CPU in one
        self.late_steal_s = {k: 0.0 for k in self.KINDS}  # host steal over the late gaps
        self.last_steal_s = 0.0  # the host's steal over the last gap
        self._steal = steal_s()

    def beat(self, now: float | None = None) -> str | None:
        """Account the gap that ends now; its class when it was late, else None."""
        now = time.perf_counter() if now is None else now
        st = _schedstat()
        if st is None:
            return None
        last, self._last = self._last, (now, st[0], st[1])
        stolen, self._steal = self._steal, steal_s()
        self.last_steal_s = (self._steal - stolen
                             if stolen is not None and self._steal is not None else 0.0)
        if last is None:
            return None
        gap = now - last[0]
        cpu = (st[0] - last[1]) / 1e9
        wait = (st[1] - last[2]) / 1e9
        self.gaps += 1
        self.cpu_s += cpu
        self.wait_s += wait
        self.longest_cpu_s = max(self.longest_cpu_s, cpu)
        for ms in self.STEP_MS:
            if cpu * 1000 > ms:
                self.steps_over[ms] += 1
        late = gap - self.period_s
        if late <= self.threshold_s:
            return None
        if cpu > self.threshold_s:
            kind = "own"
        else:
            asleep = max(gap - cpu - wait - self.period_s, 0.0)  # the timer's own wait out
            kind = "load" if wait >= asleep else "blocked"
        self.late[kind] += 1
        self.late_max_s[kind] = max(self.late_max_s[kind], late)
        self.late_cpu_s[kind] += cpu
        self.late_cpu_max_s[kind] = max(self.late_cpu_max_s[kind], cpu)
        self.late_steal_s[kind] += self.last_steal_s
        return kind

    def report_lines(self) -> list[str]:
        if not self.available:
            return ["GUI thread account: n/a (no /proc/thread-self/schedstat)"]
        wall = max(time.perf_counter() - self.t0, 1e-9)
        mins = wall / 60
        out = [f"GUI thread account over {wall:.0f} s ({self.gaps} beats): CPU "
               f"{1000 * self.cpu_s / wall:.1f} ms per s, run-queue wait "
               f"{1000 * self.wait_s / wall:.1f} ms per s; longest CPU between two beats "
               f"{1000 * self.longest_cpu_s:.1f} ms; gaps with over "
               + ", ".join(f"{ms}" for ms in self.STEP_MS) + " ms of its CPU: "
               + ", ".join(f"{self.steps_over[ms]}" for ms in self.STEP_MS)]
        for kind, what in (("own", "the GUI thread's own work (CPU in the gap over "
                            f"{self.threshold_s * 1000:.0f} ms)"),
                           ("load", "not scheduled (run-queue wait: machine load)"),
                           ("blocked", "asleep (GIL held elsewhere, a blocking call)")):
            out.append(f"  late gaps, {what}: {self.late[kind]} ({self.late[kind] / mins:.2f} "
                       f"per min), longest {1000 * self.late_max_s[kind]:.0f} ms late; the "
                       f"GUI thread's CPU in one at most {1000 * self.late_cpu_max_s[kind]:.0f} ms"
                       f"; the host's steal over them {1000 * self.late_steal_s[kind]:.0f} ms")
        return out
