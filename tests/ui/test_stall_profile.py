"""The stall profiler (bench/stall_profile.py) names what blocked the GUI thread."""

import threading
import time

import pytest
from PySide6.QtCore import QTimer

from bench.stall_profile import StallSampler

pytestmark = pytest.mark.gui


def _held_s(sampler: StallSampler) -> float:
    """Stalled time the sampler put on the holding function's line."""
    return sum(s for where, s in list(sampler.by_own.items()) if "_hold_the_gui_thread" in where)


def _hold_the_gui_thread(sampler: StallSampler, until_s: float = 0.2) -> None:
    """Busy on the GUI thread until the sampler has put ``until_s`` of stall on it
    (on a loaded machine other stalls, in the event loop's wait, come as well)."""
    end = time.monotonic() + 20.0
    while _held_s(sampler) < until_s and time.monotonic() < end:
        sum(range(1000))


def test_a_blocked_gui_thread_is_reported_at_the_blocking_line(qtbot):
    sampler = StallSampler(events=False).start()
    try:
        qtbot.waitUntil(lambda: sampler._thread.is_alive())
        QTimer.singleShot(0, lambda: _hold_the_gui_thread(sampler))
        qtbot.waitUntil(lambda: _held_s(sampler) >= 0.2, timeout=30_000)
    finally:
        sampler.stop()
    assert sampler.stalls >= 1
    # the blocking line is named; on a quiet machine it is the only one
    where = [w for w in sampler.by_own if "_hold_the_gui_thread" in w]
    assert _held_s(sampler) >= 0.2 and all("test_stall_profile.py" in w for w in where)
    report = sampler.report()
    assert "stall profile" in report and "_hold_the_gui_thread" in report


def _busy(s: float) -> None:
    end = time.thread_time() + s
    while time.thread_time() < end:
        sum(range(1000))


def test_the_ledger_tells_the_gui_threads_own_work_from_a_sleep(qtbot):
    """A late beat after the GUI thread computed 150 ms is its own work; after it
    slept 150 ms (as when it waits for the GIL or a blocking call) it is not."""
    sampler = StallSampler(events=False).start()
    if not sampler.ledger.available:
        sampler.stop()
        pytest.skip("no /proc/thread-self/schedstat on this platform")
    try:
        qtbot.waitUntil(lambda: sampler.ledger.gaps >= 3, timeout=10_000)
        QTimer.singleShot(0, lambda: _busy(0.15))
        qtbot.waitUntil(lambda: sampler.ledger.late["own"] >= 1, timeout=30_000)
        assert sampler.ledger.late_cpu_max_s["own"] >= 0.12
        asleep = sampler.ledger.late["blocked"] + sampler.ledger.late["load"]
        QTimer.singleShot(0, lambda: time.sleep(0.15))
        qtbot.waitUntil(lambda: sampler.ledger.late["blocked"] + sampler.ledger.late["load"]
                        > asleep, timeout=30_000)
    finally:
        sampler.stop()
    assert sampler.ledger.late["own"] == 1  # the sleep was not put on the GUI thread's work
    assert "own work" in sampler.report()


def test_collection_pauses_are_listed_and_own_gaps_they_filled_counted(qapp, monkeypatch):
    """Each collection's pause is kept by generation; a late gap of the GUI thread's own
    work that a collection on the GUI thread took half of is counted as one."""
    sampler = StallSampler(events=False, threshold_ms=4.0)  # not started: fed by hand
    monkeypatch.setattr(sampler.ledger, "beat", lambda now=None: "own")
    for gen, busy_s in ((0, 0.0), (2, 0.01)):
        sampler._on_gc("start", {"generation": gen})
        end = time.perf_counter() + busy_s
        while time.perf_counter() < end:  # the collection's pause
            pass
        sampler._on_gc("stop", {"generation": gen, "collected": 0, "uncollectable": 0})
    sampler._on_beat()  # a gap with 10 ms of collection in it: over half the threshold
    sampler._on_gc("start", {"generation": 0})
    sampler._on_gc("stop", {"generation": 0, "collected": 0, "uncollectable": 0})
    sampler._on_beat()  # a gap with next to none
    assert [g for g, _ in sampler.gc_pauses] == [0, 2, 0]
    assert sampler.gc_pauses[1][1] >= 0.01
    assert sampler.own_gc == 1
    lines = "\n".join(sampler.gc_pause_lines())
    assert "gen0 pauses: 2" in lines and "gen2 pauses: 1" in lines
    assert "collection in them: 1" in lines


def test_a_late_gap_is_put_on_the_thread_that_ran_in_it():
    """A thread that runs while the GUI thread waits is named with the CPU it ran."""
    from bench.gap_threads import GapThreads

    gaps = GapThreads()
    go, stop = threading.Event(), threading.Event()

    def _busy_elsewhere():
        go.wait()
        end = time.thread_time() + 0.08
        while time.thread_time() < end:
            pass
        stop.wait()

    t = threading.Thread(target=_busy_elsewhere, name="busy-elsewhere")
    t.start()
    try:
        gaps.snapshot(time.perf_counter())
        start = time.perf_counter()
        go.set()
        while t.is_alive() and not _ran_08(t):
            time.sleep(0.01)
        gaps.note_stacks((__file__,), lambda f: f)
        end = time.perf_counter()
        gaps.late(start, end, "blocked")
        time.sleep(0.002)
        gaps.snapshot(time.perf_counter())
    finally:
        stop.set()
        t.join()
    assert gaps.count == 1
    assert gaps.cpu_in_gaps["busy-elsewhere"] >= 0.07
    assert any("_busy_elsewhere" in line for line in gaps.lines_in_gaps)
    assert "busy-elsewhere" in "\n".join(gaps.report_lines(0.02))


def _ran_08(t: threading.Thread) -> bool:
    try:
        with open(f"/proc/self/task/{t.native_id}/schedstat") as f:
            return int(f.read().split()[0]) >= 80_000_000
    except OSError:
        return True


@pytest.mark.skipif(not __import__("bench.stall_profile", fromlist=["_SYSCALLS"])._SYSCALLS,
                    reason="system call names known for Linux x86_64 and aarch64 only")
def test_an_asleep_thread_is_seen_in_its_wait_and_a_late_gap_named_by_it(qapp):
    """A thread waiting for a lock is seen in a futex; one sleeping, in a sleep; a late
    asleep gap is counted under what the GUI thread was seen waiting in."""
    from bench.stall_profile import WAIT_KIND, syscall_of

    lock, ready = threading.Lock(), threading.Event()
    lock.acquire()
    tids = {}

    def _wait_for_lock():
        tids["lock"] = threading.get_native_id()
        ready.set()
        with lock:
            pass

    t = threading.Thread(target=_wait_for_lock)
    t.start()
    ready.wait()
    seen = ""
    end = time.monotonic() + 5
    while seen != "futex" and time.monotonic() < end:
        time.sleep(0.01)
        seen = syscall_of(tids["lock"])
    lock.release()
    t.join()
    assert seen == "futex" and WAIT_KIND[seen] == "GIL or lock"

    sleeper = threading.Thread(target=time.sleep, args=(0.5,))
    sleeper.start()
    end = time.monotonic() + 5
    while "sleep" not in (seen := syscall_of(sleeper.native_id)) and time.monotonic() < end:
        time.sleep(0.01)
    sleeper.join()
    assert "sleep" in seen

    sampler = StallSampler(events=False)  # not started: fed by hand
    sampler._note_blocked(["futex", "futex"], 0.08)
    sampler._note_blocked(["ppoll"], 0.06)
    sampler._note_blocked([], 0.055)
    assert sampler.blocked_in == {"futex (GIL or lock)": 1, "ppoll (event loop)": 1,
                                  "not sampled": 1}
    assert "futex (GIL or lock)" in sampler.report()
