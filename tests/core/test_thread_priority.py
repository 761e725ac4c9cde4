"""Background threads run at a lower priority than the thread that made them."""

import sys
import threading

import pytest

from app.core.thread_priority import BACKGROUND_NICE, lower_this_thread, thread_nice

linux_only = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="per-thread nice values are Linux's")


def _in_thread(fn):
    out = {}

    def run():
        out["tid"] = threading.get_native_id()
        out["before"] = thread_nice()
        out["result"] = fn()
        out["after"] = thread_nice()
        out["again"] = lower_this_thread()
        out["after_again"] = thread_nice()

    t = threading.Thread(target=run)
    t.start()
    t.join(10)
    return out


@linux_only
def test_only_the_calling_thread_is_lowered_and_only_once():
    main_before = thread_nice()
    out = _in_thread(lower_this_thread)
    assert out["result"] is True
    assert out["after"] == min(19, out["before"] + BACKGROUND_NICE)
    assert out["again"] is True and out["after_again"] == out["after"]  # not twice
    assert thread_nice() == main_before  # the caller's own thread is untouched


@linux_only
def test_the_desk_helpers_lower_their_threads(tmp_path):
    from app.core.records.archive import Archive

    main = thread_nice()
    arch = Archive(tmp_path / "a.sqlite")
    try:
        tid = arch._thread.native_id
        deadline = threading.Event()
        for _ in range(100):  # the writer lowers itself as it starts
            if thread_nice(tid) == min(19, main + BACKGROUND_NICE):
                break
            deadline.wait(0.05)
        assert thread_nice(tid) == min(19, main + BACKGROUND_NICE)
    finally:
        arch.close()
