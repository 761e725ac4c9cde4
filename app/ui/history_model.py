"""The history view's model: a time range of the archive, read off the GUI thread.

:class:`HistoryModel` holds the range, the channels to plot and the cursor (the
moment the operator is looking at). :meth:`HistoryModel.load` queries the
archive on a worker thread (``Archive.series`` down-samples long ranges to
min/max buckets) and hands the results back with ``series_loaded`` and
``journal_loaded``; ``loading`` says when a query is under way so the view can
show progress when it takes long. The journal merges alarm transitions,
events and operator commands into one time-ordered list
(:func:`journal_entries`, no Qt).
"""

from __future__ import annotations

import functools
import json
import logging
import math
import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from PySide6.QtCore import QObject, Signal

from app.core.desk.fws import TEB_EVENT
from app.core.i18n import QT_TRANSLATE_NOOP
from app.gui_jobs import GuiJobs

log = logging.getLogger(__name__)

__all__ = ["PRESETS", "HistoryModel", "JournalEntry", "SeriesData", "journal_entries"]

# name -> seconds back from the end of the recording (or now)
# the names are shown translated (context HistoryView)
PRESETS: dict[str, float] = {QT_TRANSLATE_NOOP("HistoryView", "Last hour"): 3600.0,
                             QT_TRANSLATE_NOOP("HistoryView", "Last shift (8 h)"): 8 * 3600.0,
                             QT_TRANSLATE_NOOP("HistoryView", "Last day"): 86400.0}
MAX_POINTS = 2000


@dataclass
class SeriesData:
    channel: str
    t: np.ndarray
    mean: np.ndarray
    vmin: np.ndarray
    vmax: np.ndarray

    @property
    def downsampled(self) -> bool:
        return bool(np.any(self.vmax > self.vmin))


@dataclass(frozen=True)
class JournalEntry:
    t: float
    kind: str  # "alarm" or the event's kind
    source: str
    text: str
    severity: str = ""  # alarm priority name, or the event's level


def _get(obj: Any, name: str, default: Any = None) -> Any:
    if isinstance(obj, Mapping):
        return obj.get(name, default)
    return getattr(obj, name, default)


def journal_entries(transitions: Iterable[Any], events: Iterable[Any],
                    commands: Iterable[Any] = ()) -> list[JournalEntry]:
    """Alarm transitions, events and operator commands as one list, oldest first."""
    out: list[JournalEntry] = []
    for c in commands:
        args = _get(c, "args") or {}
        text = str(_get(c, "command", "?"))
        if isinstance(args, Mapping) and args:
            text += " " + ", ".join(f"{k}={v}" for k, v in list(args.items())[:4])
        acked = _get(c, "acked")
        if acked is True:
            text += " — done"
        elif acked is False:
            text += f" — refused: {_get(c, 'ack_reason') or 'no reason given'}"
        else:
            text += " — no answer recorded"
        out.append(JournalEntry(float(_get(c, "t", 0.0)), "command",
                                str(_get(c, "user") or ""), text,
                                "warning" if acked is False else ""))
    for r in transitions:
        frm, to = str(_get(r, "from_state", "")), str(_get(r, "to_state", ""))
        who = _get(r, "user")
        why = _get(r, "reason")
        text = f"{_get(r, 'text', '') or _get(r, 'alarm', '')}: {frm} → {to}"
        if who:
            text += f" by {who}"
        if why:
            text += f" ({why})"
        out.append(JournalEntry(float(_get(r, "t", 0.0)), "alarm",
                                str(_get(r, "source", "") or ""), text,
                                str(_get(r, "priority", "") or "")))
    for ev in events:
        data = _get(ev, "data") or {}
        if isinstance(data, str):
            try:
                data = json.loads(data)
            except ValueError:
                data = {"text": data}
        kind = str(_get(ev, "kind", "event"))
        if kind == TEB_EVENT:  # a TEB plan a second while a 4WS robot drives: map data
            continue
        if isinstance(data, Mapping):
            text = str(data.get("text") or data.get("state") or data.get("code") or "")
            if not text:
                text = ", ".join(f"{k}={v}" for k, v in list(data.items())[:4]
                                 if not isinstance(v, (list, dict)))
            level = str(data.get("level", ""))
            source = str(data.get("source", kind))
        else:
            text, level, source = str(data), "", kind
        out.append(JournalEntry(float(_get(ev, "t", 0.0)), kind, source, text, level))
    out.sort(key=lambda e: e.t)
    return out


def _query(archive: Any, channels: list[str], t0: float, t1: float,
           max_points: int) -> tuple[list[SeriesData], list[JournalEntry]]:
    """The range's series and journal (on the model's pool; app/gui_jobs)."""
    series = []
    for ch in channels:
        s = archive.series(ch, t0, t1, max_points=max_points)
        series.append(SeriesData(ch, np.asarray(s.t, float), np.asarray(s.mean, float),
                                 np.asarray(s.vmin, float), np.asarray(s.vmax, float)))
    journal = journal_entries(archive.alarm_transitions(t0, t1), archive.events(t0, t1),
                              archive.commands(t0, t1))
    return series, journal


class HistoryModel(QObject):
    """A time range of one archive, the channels shown and a cursor."""

    range_changed = Signal(float, float)
    loading = Signal(bool)
    series_loaded = Signal(object)  # list[SeriesData]
    journal_loaded = Signal(object)  # list[JournalEntry]
    cursor_moved = Signal(float)
    failed = Signal(str)

    def __init__(self, archive: Any = None, parent: QObject | None = None, *,
                 max_points: int = MAX_POINTS) -> None:
        super().__init__(parent)
        self.archive = archive
        self.max_points = max_points
        now = time.time()
        self.t0, self.t1 = now - 3600.0, now
        self.channels: list[str] = []
        self.series: list[SeriesData] = []
        self.journal: list[JournalEntry] = []
        self.cursor: float | None = None
        self.busy = False
        self.queries = 0
        self._gen = 0
        # queries run on the model's own pool; a model deleted during one waits for it
        # and gets no result (app/gui_jobs)
        self._jobs = GuiJobs(self)

    # ------------------------------------------------------------ archive
    def set_archive(self, archive: Any) -> None:
        self.archive = archive

    def available_channels(self) -> list[str]:
        if self.archive is None:
            return []
        try:
            return list(self.archive.channels())
        except Exception as e:
            self.failed.emit(f"cannot list the channels: {e}")
            return []

    def recorded_range(self) -> tuple[float, float] | None:
        if self.archive is None:
            return None
        try:
            r = self.archive.time_range()
        except Exception as e:
            self.failed.emit(f"cannot read the archive's time range: {e}")
            return None
        return None if r is None else (float(r[0]), float(r[1]))

    # ------------------------------------------------------------ range
    def set_range(self, t0: float, t1: float) -> None:
        t0, t1 = float(t0), float(t1)
        if not (math.isfinite(t0) and math.isfinite(t1)) or t1 <= t0:
            raise ValueError(f"the range must end after it starts ({t0} .. {t1})")
        self.t0, self.t1 = t0, t1
        self.range_changed.emit(t0, t1)

    def apply_preset(self, name: str, end: float | None = None) -> tuple[float, float]:
        """A preset range that ends at ``end`` (default: the end of the recording,
        or now when the archive is empty)."""
        span = PRESETS[name]
        if end is None:
            rec = self.recorded_range()
            end = rec[1] if rec is not None else time.time()
        self.set_range(end - span, end)
        return self.t0, self.t1

    def set_channels(self, channels: Iterable[str]) -> None:
        self.channels = list(dict.fromkeys(channels))

    # ------------------------------------------------------------ loading
    def load(self) -> None:
        """Query the range off the GUI thread; a newer load supersedes an older one."""
        if self.archive is None:
            self.failed.emit("no archive is open")
            return
        self._gen += 1
        self.queries += 1
        self.busy = True
        self.loading.emit(True)
        self._jobs.start(functools.partial(_query, self.archive, list(self.channels), self.t0,
                                           self.t1, self.max_points),
                         functools.partial(self._on_done, self._gen),
                         functools.partial(self._on_failed, self._gen))

    def wait(self, timeout_ms: int = 10000) -> bool:
        return self._jobs.wait(timeout_ms)

    def _on_done(self, gen: int, result: tuple[list[SeriesData], list[JournalEntry]]) -> None:
        series, journal = result
        if gen != self._gen:
            return
        self.busy = False
        self.series, self.journal = series, journal
        self.loading.emit(False)
        self.series_loaded.emit(series)
        self.journal_loaded.emit(journal)

    def _on_failed(self, gen: int, e: BaseException) -> None:
        # a damaged archive must not take the desk down
        log.error("history query failed", exc_info=(type(e), e, e.__traceback__))
        why = f"{type(e).__name__}: {e}"
        if gen != self._gen:
            return
        self.busy = False
        self.loading.emit(False)
        self.failed.emit(why)

    # ------------------------------------------------------------ cursor
    def set_cursor(self, t: float) -> None:
        self.cursor = float(t)
        self.cursor_moved.emit(self.cursor)

    def jump_to(self, entry: JournalEntry) -> None:
        """Put the cursor on a journal entry's moment (widening the range if the
        moment lies outside it)."""
        if not (self.t0 <= entry.t <= self.t1):
            half = (self.t1 - self.t0) / 2
            self.set_range(entry.t - half, entry.t + half)
            self.load()
        self.set_cursor(entry.t)

    # ------------------------------------------------------------ export
    def export_csv(self, path: str | Path, t0: float | None = None, t1: float | None = None,
                   channels: Iterable[str] | None = None) -> Path:
        """Write the channels over ``[t0, t1]`` (default: the range shown) to CSV."""
        if self.archive is None:
            raise RuntimeError("no archive is open")
        chans = list(channels) if channels is not None else list(self.channels)
        if not chans:
            raise ValueError("choose at least one channel to export")
        a = self.t0 if t0 is None else float(t0)
        b = self.t1 if t1 is None else float(t1)
        if b <= a:
            raise ValueError("the export range must end after it starts")
        self.archive.export_csv(chans, a, b, str(path))
        return Path(path)

    def shutdown(self) -> None:
        self._gen += 1
        self._jobs.wait(5000)
