"""Waiting in tests for something another thread or process does: poll a
condition until it holds, and fail with a message after a deadline."""

from __future__ import annotations

import time
from collections.abc import Callable


def wait_until(pred: Callable[[], object], timeout: float = 5.0, interval: float = 0.01,
               what: str | Callable[[], str] = "condition"):
    """Poll ``pred`` every ``interval`` s until it returns something truthy
    (returned); after ``timeout`` s raise AssertionError naming ``what`` (a
    string, or a function giving one, e.g. a log to show)."""
    end = time.monotonic() + timeout
    while True:
        v = pred()
        if v:
            return v
        if time.monotonic() > end:
            text = what() if callable(what) else what
            raise AssertionError(f"{text} not met within {timeout} s")
        time.sleep(interval)
