"""Timers that must not fire together: a periodic timer started at a chosen point
of its period.

A QTimer is coarse by default: Qt may fire it up to 5 % early or late so that
timers wake the program together, and on Linux a coarse timer of a whole second
fires on a whole or half second of the monotonic clock, whoever started it and
when. Two views that each redraw once a second then do their work in the same
pass of the event loop, and their costs add up into one long slice of the GUI
thread (on the desk, the plots' refresh and paint and the alarm list's values:
about 20 ms each second). :func:`start_at_phase` starts a timer as a precise one
whose ticks fall ``phase_s`` after each whole multiple of its interval on the
monotonic clock, so a quarter-second phase keeps it clear of the coarse
once-a-second timers on either side.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from PySide6.QtCore import Qt, QTimer

__all__ = ["start_at_phase"]


def start_at_phase(timer: QTimer, phase_s: float,
                   clock: Callable[[], float] = time.monotonic, *,
                   slack_ms: int = 5) -> int:
    """Start ``timer`` (its interval set, not single-shot) precise, its ticks at
    the times ``t`` with ``t mod interval == phase_s`` on ``clock`` (the monotonic
    clock Qt's timers run on). A tick that came more than ``slack_ms`` off its
    point (the first one, or one after a stall: a precise timer late by more than
    its interval starts its count again from then) sets the next one back on it.
    Returns the milliseconds to the first tick."""
    period_ms = timer.interval()
    if period_ms <= 0 or timer.isSingleShot():
        raise ValueError("start_at_phase needs a periodic timer with an interval")

    def to_next_ms() -> int:
        """Milliseconds from now to the next point of the phase (1..period)."""
        return period_ms - int(((clock() - phase_s) * 1000) % period_ms) or period_ms

    def keep_phase() -> None:
        wait = to_next_ms()
        if wait < period_ms - slack_ms and wait > slack_ms:  # off its point: back on it
            timer.setInterval(wait)
        elif timer.interval() != period_ms:
            timer.setInterval(period_ms)  # (setInterval restarts the timer from now)

    timer.setTimerType(Qt.TimerType.PreciseTimer)
    timer.timeout.connect(keep_phase)
    first = to_next_ms()
    timer.setInterval(first)
    timer.start()
    return first
