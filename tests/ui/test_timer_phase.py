"""Periodic view timers started at a chosen point of their period, so two of them
that each do a few milliseconds of work once a second do not do it in one slice."""

from __future__ import annotations

import time

import pytest
from PySide6.QtCore import Qt, QTimer

from app.widgets.timer_phase import start_at_phase


def test_the_first_tick_lands_on_the_phase_and_a_late_tick_is_set_back_on_it(qtbot):
    now = {"t": 10.9}
    timer = QTimer()
    timer.setInterval(1000)
    ticks = []
    timer.timeout.connect(lambda: ticks.append(now["t"]))
    first = start_at_phase(timer, 0.25, clock=lambda: now["t"])
    try:
        assert first == 350  # 10.9 s -> 11.25 s
        assert timer.isActive() and timer.timerType() == Qt.TimerType.PreciseTimer
        assert timer.interval() == 350
        now["t"] = 11.252  # on its point (within the slack): the plain period from now
        timer.timeout.emit()
        assert timer.interval() == 1000
        now["t"] = 12.31  # 60 ms late (a stalled loop): the next tick back at 13.25
        timer.timeout.emit()
        assert timer.interval() == 940
        now["t"] = 13.251
        timer.timeout.emit()
        assert timer.interval() == 1000
        now["t"] = 14.249  # a millisecond early: left alone, no tick twice
        timer.timeout.emit()
        assert timer.interval() == 1000
        assert ticks == [11.252, 12.31, 13.251, 14.249]  # the owner's slot ran each time
    finally:
        timer.stop()


def test_a_timer_without_a_period_is_refused(qtbot):
    single = QTimer()
    single.setSingleShot(True)
    single.setInterval(500)
    with pytest.raises(ValueError):
        start_at_phase(single, 0.25)
    with pytest.raises(ValueError):
        start_at_phase(QTimer(), 0.25)  # interval 0


def test_the_alarm_list_refreshes_its_values_off_the_plots_second(qtbot):
    """The plots' once-a-second refresh is a coarse timer, which Qt puts on a whole
    or half second; the alarm list's value refresh is precise, a quarter past."""
    from app.core.alarms import AlarmMonitor, LimitRule
    from app.ui.alarm_panel import AlarmPanel

    panel = AlarmPanel(AlarmMonitor([LimitRule("temp_c", high=45.0)]), user="ana")
    qtbot.addWidget(panel)
    timer = panel._values
    assert timer.isActive() and timer.timerType() == Qt.TimerType.PreciseTimer
    due = (time.monotonic() + timer.remainingTime() / 1000) % 1.0
    assert abs(due - 0.25) < 0.1  # computed from the clock, not waited for
