"""The history view: a thin view over :class:`~app.ui.history_model.HistoryModel`.

Top: a range preset (last hour, shift, day) or from/to (UTC), *Show*, and CSV
export of the visible range (or of the from/to range). Left: the channels to
plot. Middle: one plot per channel, stacked with a shared time axis; long ranges
arrive down-sampled and show the min–max band behind the mean. Right: the alarm
and event journal; clicking a line moves the cursor (a vertical line across
every plot) to that moment. A progress bar appears when a query takes more
than a second.
"""

from __future__ import annotations

import logging
from datetime import UTC, datetime

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import QDateTime, Qt, QTimer, QTimeZone, Signal
from PySide6.QtWidgets import (
    QAbstractItemView,
    QComboBox,
    QDateTimeEdit,
    QFileDialog,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QListWidget,
    QListWidgetItem,
    QProgressBar,
    QPushButton,
    QSplitter,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from app.core.i18n import QT_TRANSLATE_NOOP, translate
from app.ui.history_model import PRESETS, HistoryModel, JournalEntry, SeriesData

log = logging.getLogger(__name__)

__all__ = ["HistoryView"]

CUSTOM = QT_TRANSLATE_NOOP("HistoryView", "From / to")
SEVERITY_COLOURS = {"EMERGENCY": "#c8102e", "HIGH": "#c8102e", "MEDIUM": "#f08c00",
                    "LOW": "#b59a00", "alarm": "#c8102e", "warning": "#f08c00"}


def _utc_text(t: float) -> str:
    return datetime.fromtimestamp(t, UTC).strftime("%Y-%m-%d %H:%M:%S")


def _to_qdt(t: float) -> QDateTime:
    return QDateTime.fromMSecsSinceEpoch(int(t * 1000), QTimeZone.utc())


class HistoryView(QWidget):
    """Plots, journal and export over one archive's time range."""

    export_written = Signal(str)

    def __init__(self, model: HistoryModel, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self.last_error = ""

        # ---- range bar
        self.preset = QComboBox(self)
        for name in [*PRESETS, CUSTOM]:  # shown translated, the preset's name kept as data
            self.preset.addItem(translate("HistoryView", name), name)
        self.preset.setToolTip(self.tr("Range of the recording to show"))
        self.from_edit = QDateTimeEdit(self)
        self.to_edit = QDateTimeEdit(self)
        for e in (self.from_edit, self.to_edit):
            e.setTimeZone(QTimeZone.utc())
            e.setDisplayFormat("yyyy-MM-dd HH:mm:ss 'UTC'")
            e.setCalendarPopup(True)
        self.show_button = QPushButton(self.tr("Show"), self)
        self.show_button.setToolTip(self.tr("Load the chosen range (Enter)"))
        self.export_button = QPushButton(self.tr("Export CSV…"), self)
        self.export_button.setToolTip(self.tr("Export the visible range of the shown channels"))
        self.export_range_button = QPushButton(self.tr("Export from/to…"), self)
        self.export_range_button.setToolTip(
            self.tr("Export the from/to range of the shown channels"))
        self.progress = QProgressBar(self)
        self.progress.setRange(0, 0)
        self.progress.setMaximumWidth(120)
        self.progress.setVisible(False)
        self.status = QLabel("", self)
        bar = QHBoxLayout()
        bar.addWidget(self.preset)
        bar.addWidget(QLabel(self.tr("from"), self))
        bar.addWidget(self.from_edit)
        bar.addWidget(QLabel(self.tr("to"), self))
        bar.addWidget(self.to_edit)
        bar.addWidget(self.show_button)
        bar.addWidget(self.progress)
        bar.addStretch(1)
        bar.addWidget(self.status)
        bar.addWidget(self.export_button)
        bar.addWidget(self.export_range_button)

        # ---- channels, plots, journal
        self.channel_list = QListWidget(self)
        self.channel_list.setMaximumWidth(180)
        self.plots = pg.GraphicsLayoutWidget(self)
        self.journal = QTableWidget(0, 4, self)
        self.journal.setHorizontalHeaderLabels([self.tr("Time (UTC)"), self.tr("Kind"),
                                                self.tr("Source"), self.tr("What")])
        self.journal.verticalHeader().setVisible(False)
        self.journal.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.journal.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.journal.horizontalHeader().setSectionResizeMode(
            3, QHeaderView.ResizeMode.Stretch)
        split = QSplitter(Qt.Orientation.Horizontal, self)
        split.addWidget(self.channel_list)
        split.addWidget(self.plots)
        split.addWidget(self.journal)
        split.setStretchFactor(1, 3)
        split.setStretchFactor(2, 2)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        lay.addLayout(bar)
        lay.addWidget(split, 1)

        self._in_preset = False
        self._plot_items: dict[str, pg.PlotItem] = {}
        self._cursor_lines: list[pg.InfiniteLine] = []
        self._busy_timer = QTimer(self)
        self._busy_timer.setSingleShot(True)
        self._busy_timer.timeout.connect(lambda: self.progress.setVisible(self.model.busy))

        # ---- wiring
        self.preset.currentIndexChanged.connect(
            lambda i: self._on_preset(self.preset.itemData(i)))
        self.show_button.clicked.connect(self.apply_range)
        self.export_button.clicked.connect(lambda: self._ask_export(visible=True))
        self.export_range_button.clicked.connect(lambda: self._ask_export(visible=False))
        self.journal.cellClicked.connect(lambda row, _col: self.jump_to_row(row))
        self.channel_list.itemChanged.connect(lambda _i: self._channels_changed())
        model.range_changed.connect(self._show_range)
        model.loading.connect(self._on_loading)
        model.series_loaded.connect(self._on_series)
        model.journal_loaded.connect(self._on_journal)
        model.cursor_moved.connect(self._on_cursor)
        model.failed.connect(self._on_failed)
        self._show_range(model.t0, model.t1)

    # ------------------------------------------------------------ actions
    def refresh_channels(self, checked: list[str] | None = None) -> None:
        """Fill the channel list from the archive; ``checked`` (default: the
        model's channels, or the first one) are ticked."""
        names = self.model.available_channels()
        want = set(checked if checked is not None else (self.model.channels or names[:1]))
        self.channel_list.blockSignals(True)
        self.channel_list.clear()
        for n in names:
            it = QListWidgetItem(n, self.channel_list)
            it.setFlags(it.flags() | Qt.ItemFlag.ItemIsUserCheckable)
            it.setCheckState(Qt.CheckState.Checked if n in want else Qt.CheckState.Unchecked)
        self.channel_list.blockSignals(False)
        self.model.set_channels([n for n in names if n in want])

    def checked_channels(self) -> list[str]:
        out = []
        for i in range(self.channel_list.count()):
            it = self.channel_list.item(i)
            if it.checkState() == Qt.CheckState.Checked:
                out.append(it.text())
        return out

    def set_channel_checked(self, name: str, on: bool = True) -> None:
        for i in range(self.channel_list.count()):
            it = self.channel_list.item(i)
            if it.text() == name:
                it.setCheckState(Qt.CheckState.Checked if on else Qt.CheckState.Unchecked)

    def _channels_changed(self) -> None:
        self.model.set_channels(self.checked_channels())
        self.model.load()

    def _on_preset(self, name: str) -> None:
        if name in PRESETS:
            self.select_preset(name)

    def select_preset(self, name: str) -> None:
        """Show a preset range (last hour, shift, day) and load it."""
        self._in_preset = True
        try:
            self.preset.blockSignals(True)
            self.preset.setCurrentIndex(self.preset.findData(name))
            self.preset.blockSignals(False)
            self.model.apply_preset(name)
        finally:
            self._in_preset = False
        self.model.load()

    def apply_range(self) -> None:
        """Load the from/to range."""
        t0 = self.from_edit.dateTime().toMSecsSinceEpoch() / 1000.0
        t1 = self.to_edit.dateTime().toMSecsSinceEpoch() / 1000.0
        try:
            self.model.set_range(t0, t1)
        except ValueError as e:
            self._on_failed(str(e))
            return
        self.preset.blockSignals(True)
        self.preset.setCurrentIndex(self.preset.findData(CUSTOM))
        self.preset.blockSignals(False)
        self.model.load()

    def visible_range(self) -> tuple[float, float]:
        """The time range the plots show now (after zooming/panning), within
        the loaded range."""
        if self._plot_items:
            p = next(iter(self._plot_items.values()))
            (a, b), _ = p.viewRange()
            a, b = max(a, self.model.t0), min(b, self.model.t1)
            if b > a:
                return float(a), float(b)
        return self.model.t0, self.model.t1

    def export_visible(self, path: str) -> str:
        t0, t1 = self.visible_range()
        self.model.export_csv(path, t0, t1)
        self.export_written.emit(path)
        self.status.setText(self.tr("exported {t0} – {t1}").format(t0=_utc_text(t0),
                                                                   t1=_utc_text(t1)))
        return path

    def export_chosen(self, path: str) -> str:
        t0 = self.from_edit.dateTime().toMSecsSinceEpoch() / 1000.0
        t1 = self.to_edit.dateTime().toMSecsSinceEpoch() / 1000.0
        self.model.export_csv(path, t0, t1)
        self.export_written.emit(path)
        self.status.setText(self.tr("exported {t0} – {t1}").format(t0=_utc_text(t0),
                                                                   t1=_utc_text(t1)))
        return path

    def _ask_export(self, *, visible: bool) -> None:
        path, _ = QFileDialog.getSaveFileName(self, self.tr("Export CSV"), "history.csv",
                                              self.tr("CSV files (*.csv)"))
        if not path:
            return
        try:
            (self.export_visible if visible else self.export_chosen)(path)
        except (OSError, ValueError, RuntimeError) as e:
            self._on_failed(self.tr("export failed: {why}").format(why=e))

    def jump_to_row(self, row: int) -> None:
        if 0 <= row < len(self.model.journal):
            self.model.jump_to(self.model.journal[row])

    # ------------------------------------------------------------ model slots
    def _show_range(self, t0: float, t1: float) -> None:
        if not self._in_preset:  # set by from/to or a jump: no longer a preset
            self.preset.blockSignals(True)
            self.preset.setCurrentIndex(self.preset.findData(CUSTOM))
            self.preset.blockSignals(False)
        for e, t in ((self.from_edit, t0), (self.to_edit, t1)):
            e.blockSignals(True)
            e.setDateTime(_to_qdt(t))
            e.blockSignals(False)

    def _on_loading(self, on: bool) -> None:
        if on:
            self.status.setText(self.tr("loading…"))
            self._busy_timer.start(1000)
        else:
            self._busy_timer.stop()
            self.progress.setVisible(False)
            self.status.setText("")

    def _on_failed(self, why: str) -> None:
        self.last_error = why
        self.status.setText(why)
        log.warning("history: %s", why)

    def _on_series(self, series: list[SeriesData]) -> None:
        self.plots.clear()
        self._plot_items.clear()
        self._cursor_lines.clear()
        first: pg.PlotItem | None = None
        for i, s in enumerate(series):
            p = self.plots.addPlot(row=i, col=0,
                                   axisItems={"bottom": pg.DateAxisItem(utcOffset=0)})
            p.setLabel("left", s.channel)
            p.showGrid(x=True, y=True, alpha=0.2)
            p.setXRange(self.model.t0, self.model.t1, padding=0)
            if first is None:
                first = p
            else:
                p.setXLink(first)
            if len(s.t):
                if s.downsampled:
                    lo = pg.PlotDataItem(s.t, s.vmin, pen=pg.mkPen("#9a9a9a"))
                    hi = pg.PlotDataItem(s.t, s.vmax, pen=pg.mkPen("#9a9a9a"))
                    p.addItem(lo)
                    p.addItem(hi)
                    p.addItem(pg.FillBetweenItem(lo, hi, brush=pg.mkBrush(46, 46, 46, 50)))
                p.plot(s.t, s.mean, pen=pg.mkPen("#2e2e2e", width=1.5))
            line = pg.InfiniteLine(angle=90, movable=False, pen=pg.mkPen("#c8102e", width=1))
            line.setVisible(self.model.cursor is not None)
            if self.model.cursor is not None:
                line.setValue(self.model.cursor)
            p.addItem(line, ignoreBounds=True)
            self._cursor_lines.append(line)
            self._plot_items[s.channel] = p
        n = sum(len(s.t) for s in series)
        self.status.setText(self.tr("{n} channel(s), {points} points").format(n=len(series),
                                                                             points=n))

    def _on_journal(self, entries: list[JournalEntry]) -> None:
        self.journal.setRowCount(len(entries))
        for row, e in enumerate(entries):
            cells = (_utc_text(e.t), e.kind, e.source, e.text)
            for col, text in enumerate(cells):
                it = QTableWidgetItem(text)
                colour = SEVERITY_COLOURS.get(e.severity)
                if colour and col == 1:
                    it.setForeground(pg.mkColor(colour))
                self.journal.setItem(row, col, it)

    def _on_cursor(self, t: float) -> None:
        for line in self._cursor_lines:
            line.setValue(t)
            line.setVisible(True)
        for p in self._plot_items.values():
            (a, b), _ = p.viewRange()
            if not a <= t <= b:
                half = (b - a) / 2
                p.setXRange(t - half, t + half, padding=0)
            break  # the plots share their x axis

    # ------------------------------------------------------------ test helpers
    def plotted(self, channel: str) -> tuple[np.ndarray, np.ndarray] | None:
        """The mean curve drawn for ``channel`` (x, y), or None."""
        p = self._plot_items.get(channel)
        if p is None:
            return None
        items = [it for it in p.listDataItems() if it.opts.get("pen") is not None]
        if not items:
            return None
        x, y = items[-1].getData()
        return np.asarray(x), np.asarray(y)

    def cursor_position(self) -> float | None:
        if not self._cursor_lines or not self._cursor_lines[0].isVisible():
            return None
        return float(self._cursor_lines[0].value())
