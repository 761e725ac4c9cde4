"""The replay transport: play/pause, a position slider, the time and the speed.

A thin view over :class:`~app.ui.replay.ReplayLink`. Keys (window-wide):
P play/pause, comma / period back / forward 10 s, [ / ] slower / faster,
Home back to the start.
"""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any

from PySide6.QtCore import Qt
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import QComboBox, QLabel, QSlider, QToolBar, QWidget

from app.core.i18n import translate
from app.core.replay import SPEEDS

__all__ = ["ReplayBar"]

SLIDER_STEPS = 1000
SEEK_STEP_S = 10.0


def _utc(t: float) -> str:
    return datetime.fromtimestamp(t, UTC).strftime("%Y-%m-%d %H:%M:%S")


class ReplayBar(QToolBar):
    def __init__(self, link: Any, parent: QWidget | None = None) -> None:
        super().__init__(translate("ReplayBar", "Replay"), parent)
        self.setObjectName("replayBar")
        self.link = link
        self.play_action = QAction(self.tr("Play"), self)
        self.play_action.setShortcut(QKeySequence("P"))
        self.play_action.setToolTip(self.tr("Play / pause (P)"))
        self.play_action.triggered.connect(link.toggle)
        self.addAction(self.play_action)
        self.back_action = QAction(self.tr("−10 s"), self)
        self.back_action.setShortcut(QKeySequence(","))
        self.back_action.setToolTip(self.tr("Back 10 s (,)"))
        self.back_action.triggered.connect(lambda: link.seek(link.position - SEEK_STEP_S))
        self.addAction(self.back_action)
        self.fwd_action = QAction(self.tr("+10 s"), self)
        self.fwd_action.setShortcut(QKeySequence("."))
        self.fwd_action.setToolTip(self.tr("Forward 10 s (.)"))
        self.fwd_action.triggered.connect(lambda: link.seek(link.position + SEEK_STEP_S))
        self.addAction(self.fwd_action)
        self.home_action = QAction(self.tr("Start"), self)
        self.home_action.setShortcut(QKeySequence("Home"))
        self.home_action.triggered.connect(lambda: link.seek(link.clock.t0))
        self.addAction(self.home_action)

        self.slider = QSlider(Qt.Orientation.Horizontal, self)
        self.slider.setRange(0, SLIDER_STEPS)
        self.slider.setMinimumWidth(300)
        self.slider.setToolTip(self.tr("Drag to seek"))
        self.addWidget(self.slider)
        self.time_label = QLabel("", self)
        self.addWidget(self.time_label)
        self.speed_box = QComboBox(self)
        for s in SPEEDS:
            self.speed_box.addItem(f"{s:g}×", s)
        self.speed_box.setToolTip(self.tr("Replay speed ([ slower, ] faster)"))
        self.addWidget(self.speed_box)
        self.slower_action = QAction(self.tr("Slower"), self)
        self.slower_action.setShortcut(QKeySequence("["))
        self.slower_action.triggered.connect(lambda: self._step_speed(-1))
        self.faster_action = QAction(self.tr("Faster"), self)
        self.faster_action.setShortcut(QKeySequence("]"))
        self.faster_action.triggered.connect(lambda: self._step_speed(+1))
        for a in (self.slower_action, self.faster_action):
            self.addAction(a)
        if parent is not None:  # the keys work anywhere in the window
            for a in (self.play_action, self.back_action, self.fwd_action, self.home_action,
                      self.slower_action, self.faster_action):
                a.setShortcutContext(Qt.ShortcutContext.WindowShortcut)
                parent.addAction(a)

        self.slider.sliderMoved.connect(self._on_slider)
        self.slider.actionTriggered.connect(lambda _a: self._on_slider(
            self.slider.sliderPosition()))
        self.speed_box.currentIndexChanged.connect(
            lambda i: link.set_speed(self.speed_box.itemData(i)))
        link.position_changed.connect(self.show_position)
        link.playing_changed.connect(self.show_playing)
        link.speed_changed.connect(self.show_speed)
        self.show_speed(link.clock.speed)
        self.show_position(link.position)

    def toolbar(self) -> QToolBar:
        return self

    def _on_slider(self, value: int) -> None:
        self.link.seek_fraction(value / SLIDER_STEPS)

    def _step_speed(self, d: int) -> None:
        i = min(len(SPEEDS) - 1, max(0, self.speed_box.currentIndex() + d))
        self.speed_box.setCurrentIndex(i)

    def show_position(self, t: float) -> None:
        c = self.link.clock
        if not self.slider.isSliderDown():
            self.slider.blockSignals(True)
            self.slider.setValue(round(c.fraction * SLIDER_STEPS))
            self.slider.blockSignals(False)
        self.time_label.setText(f"{_utc(t)} UTC  ({t - c.t0:.0f} / {c.t1 - c.t0:.0f} s)")

    def show_playing(self, on: bool) -> None:
        self.play_action.setText(self.tr("Pause") if on else self.tr("Play"))

    def show_speed(self, s: float) -> None:
        i = self.speed_box.findData(s)
        if i < 0:
            self.speed_box.addItem(f"{s:g}×", s)
            i = self.speed_box.count() - 1
        if i != self.speed_box.currentIndex():
            self.speed_box.blockSignals(True)
            self.speed_box.setCurrentIndex(i)
            self.speed_box.blockSignals(False)
