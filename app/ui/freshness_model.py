"""FreshnessModel: the Qt side of app/core/freshness (how old each robot-derived
value is).

Slots note arrivals (``note(name, value)``) and the link's state; a timer asks the
core tracker every ``tick_ms`` and announces ``changed(dict name -> Freshness)``
whenever a source's age state changes, or the age a stale source shows does (its
"N s ago", whole seconds and then whole minutes: ``age_text``), not at every tick
while one is stale: every display that shows an age is redrawn on ``changed``,
and a desk whose link was lost overnight would redraw them all twice a second
for the same words. In replay nothing is judged: the archive's values are as old
as the replay clock says, not as the desk's clock.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from PySide6.QtCore import QObject, QTimer, Signal

from app.core.freshness import Age, Freshness, FreshnessTracker, age_text

__all__ = ["FreshnessModel", "SOURCES"]

# name -> periodic: telemetry (mode, battery, gas, ...), pose and patrol status
# stream; the control lease changes only when someone takes or gives control; the
# round-trip time is the desk's own figure of the robot's answers
SOURCES: dict[str, bool] = {"telemetry": True, "pose": True, "patrol": True,
                            "control": False, "rtt": False, "video": True}
_UP_STATES = ("connected", "replay")


class FreshnessModel(QObject):
    changed = Signal(object)  # dict name -> Freshness

    def __init__(self, parent: QObject | None = None, *, tick_ms: int = 500,
                 tracker: FreshnessTracker | None = None,
                 mono: Callable[[], float] = time.monotonic) -> None:
        super().__init__(parent)
        self.tracker = tracker or FreshnessTracker(mono=mono)
        for name, periodic in SOURCES.items():
            self.tracker.expect(name, periodic=periodic)
        self.replay = False
        self._last: dict[str, Age] = {}
        self._shown: dict[str, tuple[Age, str]] = {}  # what was announced: state, age
        self._timer = QTimer(self)
        self._timer.setInterval(tick_ms)
        self._timer.timeout.connect(self.refresh)
        self._timer.start()

    # ------------------------------------------------------------ inputs
    def note(self, name: str, value: Any = None) -> None:
        self.tracker.note(name, value)
        if self._last.get(name, Age.NONE) is not Age.LIVE:
            self.refresh()

    def on_link_state(self, state: str) -> None:
        self.replay = state == "replay"
        self.tracker.set_link_up(state in _UP_STATES)
        self.refresh()

    # ------------------------------------------------------------ queries
    def freshness(self, name: str) -> Freshness:
        f = self.tracker.freshness(name)
        if self.replay and f.stale:
            return Freshness(Age.LIVE, f.age_s, f.received_utc_s)
        return f

    def snapshot(self) -> dict[str, Freshness]:
        return {name: self.freshness(name) for name in self.tracker.names()}

    @property
    def link_up(self) -> bool:
        return self.tracker.link_up

    def refresh(self) -> dict[str, Freshness]:
        """Judge every source now; announce when a state changed, or the age shown
        of a stale source."""
        snap = self.snapshot()
        self._last = {n: f.age for n, f in snap.items()}
        shown = {n: (f.age, age_text(f.age_s) if f.stale and f.age_s is not None else "")
                 for n, f in snap.items()}
        if shown != self._shown:
            self._shown = shown
            self.changed.emit(snap)
        return snap
