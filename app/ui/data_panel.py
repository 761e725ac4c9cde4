"""Data panel: live plots of gas, temperature and humidity with their warning
limits, and the current values as tiles that turn to the alarm colour of a limit
(or rate) alarm. Values no longer current (link down, telemetry quiet) are shown
stale with their age (:meth:`DataPanel.show_freshness`), never in alarm colour;
a stale-data alarm colours no tile."""

from __future__ import annotations

import numpy as np
from PySide6.QtWidgets import (
    QComboBox,
    QGridLayout,
    QHBoxLayout,
    QLabel,
    QVBoxLayout,
    QWidget,
)

from app.core.i18n import QT_TRANSLATE_NOOP, translate
from app.ui import theme
from app.ui.alarm_banner import tile_level
from app.ui.frame_batch import Coalesced
from app.ui.models import PLOT_CHANNELS, SPECS, TelemetryModel, channel_label
from app.widgets import PlotStrip, ValueTile

WINDOWS_MIN: tuple[int, ...] = (1, 10, 60)


class DataPanel(QWidget):
    def __init__(self, model: TelemetryModel, parent: QWidget | None = None, *,
                 window_min: int = 10, refresh_hz: float = 5.0) -> None:
        super().__init__(parent)
        self.model = model
        self.strip = PlotStrip(self, refresh_hz=refresh_hz, window_s=window_min * 60.0,
                               curve_color=theme.CURVE, limit_color=theme.LIMIT_LINE)
        self.tiles: dict[str, ValueTile] = {}
        tiles = QVBoxLayout()
        tiles.setSpacing(6)
        for key in PLOT_CHANNELS:
            spec = SPECS[key]
            self.strip.add_channel(key, channel_label(key), spec.unit)
            rule = model.rule(key)
            if rule is not None:
                if rule.high is not None:
                    self.strip.set_limit(key, self.tr("high {limit} {unit}").format(
                        limit=f"{rule.high:g}", unit=spec.unit), rule.high)
                if rule.low is not None:
                    self.strip.set_limit(key, self.tr("low {limit} {unit}").format(
                        limit=f"{rule.low:g}", unit=spec.unit), rule.low)
            tile = ValueTile(channel_label(key), spec.unit, self, fmt=spec.fmt)
            tile.setMinimumWidth(120)
            self.tiles[key] = tile
            tiles.addWidget(tile, 1)
        self.strip.set_source(self._source)

        self.window_box = QComboBox(self)
        for m in WINDOWS_MIN:
            self.window_box.addItem(f"{m} min", m)
        self.window_box.setCurrentIndex(
            WINDOWS_MIN.index(window_min) if window_min in WINDOWS_MIN else 1)
        self.window_box.currentIndexChanged.connect(
            lambda i: self.set_window_minutes(self.window_box.itemData(i)))
        self.window_box.setToolTip(self.tr("Time window of the plots (Ctrl+1 / Ctrl+2 / Ctrl+3)"))

        head = QHBoxLayout()
        head.addWidget(QLabel(self.tr("Window:"), self))
        head.addWidget(self.window_box)
        head.addStretch(1)
        body = QGridLayout()
        body.addLayout(tiles, 0, 0)
        body.addWidget(self.strip, 0, 1)
        body.setColumnStretch(1, 1)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        lay.addLayout(head)
        lay.addLayout(body, 1)

        # the tiles show the newest of the samples that came in one pass of the event
        # loop (the plots read every sample from the series)
        self.values_batch = Coalesced(self.show_values, self)
        model.values_changed.connect(self.values_batch.take)
        # a method, not a lambda holding the panel: the model may outlive the panel, and
        # a lambda in its connection (which the garbage collector cannot see) would keep
        # the deleted panel's plots and their menus alive with it
        model.alarm_changed.connect(self._on_alarm_change)
        self.trend_channel: str | None = None

    def set_window_minutes(self, minutes: int) -> None:
        self.strip.set_window(minutes * 60.0)
        i = self.window_box.findData(minutes)
        if i >= 0 and i != self.window_box.currentIndex():
            self.window_box.setCurrentIndex(i)

    def window_minutes(self) -> float:
        return self.strip.window_s() / 60.0

    def show_values(self, values: dict) -> None:
        for key, tile in self.tiles.items():
            tile.set_value(values.get(key))
        self.strip.mark_dirty()

    def _on_alarm_change(self, transition) -> None:
        self._on_alarm(transition.alarm)

    def _on_alarm(self, alarm) -> None:
        ch = alarm.channel or alarm.source
        if ch in self.tiles:
            self.tiles[ch].set_alarm(tile_level(self.model.value_priority(ch)) or None)
            stage = self.model.gas_stage(ch)
            if stage is not None:  # the gas detector's stage; colour stays the alarm's
                name = channel_label(ch)
                self.tiles[ch].set_label(name if stage == "normal" else
                                         f"{name} · {translate('GasStage', stage)}")

    def show_freshness(self, telemetry) -> None:
        """``telemetry``: the app.core.freshness.Freshness of the telemetry stream."""
        text = telemetry.text() or None
        for tile in self.tiles.values():
            tile.set_stale(text)

    # ------------------------------------------------------------ alarm trend
    TREND = "alarm_trend"

    def _source(self, key: str, seconds: float):
        if key == self.TREND:
            key = self.trend_channel or ""
        try:
            return self.model.window(key, seconds)
        except KeyError:  # not a telemetry series (e.g. a meter): nothing to plot
            return np.empty(0), np.empty(0)

    def show_channel(self, channel: str) -> None:
        """Show ``channel`` with its limit lines on the alarm-trend plot (added
        under the others the first time an alarm is selected)."""
        spec = SPECS.get(channel)
        label, unit = (channel_label(channel), spec.unit) if spec else (channel, "")
        if self.TREND not in self.strip.channels():
            self.strip.add_channel(self.TREND, self.tr("Alarm trend"), "")
        self.trend_channel = channel
        self.strip.plot_item(self.TREND).setLabel("left", f"▶ {label}", units=unit or None)
        self._limit_lines(self.TREND, channel, unit)
        self.strip.mark_dirty(self.TREND)

    def _limit_lines(self, key: str, channel: str, unit: str) -> None:
        for name in list(self.strip.limit_lines(key)):
            self.strip.set_limit(key, name, None)
        rule = self.model.rule(channel)
        if rule is not None:
            if rule.high is not None:
                self.strip.set_limit(key, self.tr("high {limit} {unit}").format(
                    limit=f"{rule.high:g}", unit=unit).rstrip(), rule.high)
            if rule.low is not None:
                self.strip.set_limit(key, self.tr("low {limit} {unit}").format(
                    limit=f"{rule.low:g}", unit=unit).rstrip(), rule.low)

    def update_limits(self) -> None:
        """Redraw every limit line from the current rules (after the settings change)."""
        for key in PLOT_CHANNELS:
            self._limit_lines(key, key, SPECS[key].unit)
        if self.trend_channel is not None and self.TREND in self.strip.channels():
            spec = SPECS.get(self.trend_channel)
            self._limit_lines(self.TREND, self.trend_channel, spec.unit if spec else "")


# the gas detector's stages as the tiles name them (app/core/alarms/setpoints.gas_stage)
GAS_STAGES = (QT_TRANSLATE_NOOP("GasStage", "A1"), QT_TRANSLATE_NOOP("GasStage", "A2"),
              QT_TRANSLATE_NOOP("GasStage", "over-range"), QT_TRANSLATE_NOOP("GasStage", "fault"))
