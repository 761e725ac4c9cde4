"""The stall profiler (bench/stall_profile.py) names what blocked the GUI thread."""

import time

import pytest
from PySide6.QtCore import QTimer

from bench.stall_profile import StallSampler

pytestmark = pytest.mark.gui


def _hold_the_gui_thread(sampler: StallSampler, until_s: float = 0.2) -> None:
    """Busy on the GUI thread until the sampler has seen ``until_s`` of stall."""
    end = time.monotonic() + 20.0
    while sampler.stalled_s < until_s and time.monotonic() < end:
        sum(range(1000))


def test_a_blocked_gui_thread_is_reported_at_the_blocking_line(qtbot):
    sampler = StallSampler(events=False).start()
    try:
        qtbot.waitUntil(lambda: sampler._thread.is_alive())
        QTimer.singleShot(0, lambda: _hold_the_gui_thread(sampler))
        qtbot.waitUntil(lambda: sampler.stalled_s >= 0.2, timeout=30_000)
    finally:
        sampler.stop()
    assert sampler.stalls >= 1
    (where, stalled), = sampler.by_own.most_common(1)
    assert "_hold_the_gui_thread" in where and stalled > 0.1
    report = sampler.report()
    assert "stall profile" in report and "_hold_the_gui_thread" in report
