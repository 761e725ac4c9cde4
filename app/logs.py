"""The desk's logs: the console, and rotating files in the platform's log folder.

:func:`setup_logging` sends every record to the console (stderr) and to
``station-patrol.log`` in the log folder (``--log-dir``, ``[log] dir`` in the desk TOML,
``$STATION_PATROL_LOG_DIR``, else the platform's user-log folder, see
:mod:`app.core.paths`). The file is rolled over at local midnight and whenever it reaches
``max_bytes``; rolled files (``station-patrol.log.YYYY-MM-DD_HH-MM-SS``) older than
``keep_days`` (a week by default) are deleted, and never more than ``max_files`` are
kept, so the folder stays bounded however much is logged (``max_bytes * (max_files +
1)`` at most). A log folder that cannot be written to costs the file only: the desk
says so on the console and runs on.

Alarm transitions (``app.core.alarms.monitor``) and operator commands
(``app.core.desk.gateway``) are logged at INFO, so both land in the file.
"""

from __future__ import annotations

import logging
import os
import re
import sys
import time
from dataclasses import dataclass
from logging.handlers import BaseRotatingHandler
from pathlib import Path

from app.core import paths

__all__ = ["LOG_NAME", "LogSettings", "RotatingLogHandler", "current_log_dir", "setup_logging"]

LOG_NAME = "station-patrol.log"
FORMAT = "%(asctime)s %(levelname)s %(name)s: %(message)s"
_STAMP = "%Y-%m-%d_%H-%M-%S"
_ROLLED = re.compile(r"\.(\d{4}-\d\d-\d\d_\d\d-\d\d-\d\d)(?:-(\d+))?$")

log = logging.getLogger(__name__)
_current_dir: Path | None = None


@dataclass
class LogSettings:
    """[log] in the desk TOML."""

    dir: str = ""  # "": $STATION_PATROL_LOG_DIR or the platform's user-log folder
    keep_days: float = 7.0  # rolled files older than this are deleted
    max_bytes: int = 10_000_000  # roll over at this size too (0: only at midnight)
    max_files: int = 60  # rolled files kept at most, whatever their age


class RotatingLogHandler(BaseRotatingHandler):
    """A log file rolled over at local midnight and at ``max_bytes``; the rolled files
    are pruned by age (``keep_days``) and count (``max_files``)."""

    def __init__(self, filename: str | os.PathLike, *, keep_days: float = 7.0,
                 max_bytes: int = 10_000_000, max_files: int = 60,
                 clock=time.time) -> None:
        super().__init__(os.fspath(filename), "a", encoding="utf-8", delay=False)
        self.keep_days = float(keep_days)
        self.max_bytes = int(max_bytes)
        self.max_files = int(max_files)
        self._clock = clock
        self.rollovers = 0
        self._stamp, self._n = "", 0
        self.roll_at = self._next_midnight(self._clock())
        self.prune()

    @staticmethod
    def _next_midnight(t: float) -> float:
        lt = time.localtime(t)
        midnight = time.mktime((lt.tm_year, lt.tm_mon, lt.tm_mday, 0, 0, 0, 0, 0, -1))
        return midnight + 86400 if midnight <= t else midnight

    def shouldRollover(self, record: logging.LogRecord) -> bool:  # noqa: N802 - logging API
        if self._clock() >= self.roll_at:
            return True
        if self.max_bytes > 0 and self.stream is not None:
            size = self.stream.tell()
            return size > 0 and size + len(self.format(record)) + 1 >= self.max_bytes
        return False

    def rolled_files(self) -> list[Path]:
        """The rolled files of this log, oldest first."""
        base = Path(self.baseFilename)
        found = [p for p in base.parent.glob(base.name + ".*") if _ROLLED.search(p.name)]
        def order(p: Path) -> tuple[str, int]:  # stamp, then the n-th within that second
            m = _ROLLED.search(p.name)
            return m.group(1), int(m.group(2) or 0)

        return sorted(found, key=order)

    def doRollover(self) -> None:  # noqa: N802 - logging API
        if self.stream is not None:
            self.stream.close()
            self.stream = None
        base = Path(self.baseFilename)
        stamp = time.strftime(_STAMP, time.localtime(self._clock()))
        # the n-th rollover within one second gets "-n" (counted on, never reused even
        # when an earlier one of that second was pruned, so the order stays true)
        self._n = self._n + 1 if stamp == self._stamp else 0
        self._stamp = stamp
        while True:
            target = base.with_name(f"{base.name}.{stamp}" + (f"-{self._n}" if self._n else ""))
            if not target.exists():
                break
            self._n += 1
        try:
            if base.exists():
                os.replace(base, target)
        except OSError as e:  # e.g. another program holds the file open (Windows)
            log.warning("log file not rolled over: %s", e)
        self.stream = self._open()
        self.rollovers += 1
        self.roll_at = self._next_midnight(self._clock())
        self.prune()

    def prune(self) -> None:
        """Delete rolled files older than ``keep_days`` and all but the newest
        ``max_files``."""
        files = self.rolled_files()
        cutoff = self._clock() - self.keep_days * 86400
        old = [p for p in files if _mtime(p) < cutoff]
        keep = [p for p in files if p not in old]
        extra = keep[:max(0, len(keep) - self.max_files)]
        for p in old + extra:
            try:
                p.unlink()
            except OSError as e:
                log.warning("old log file %s not deleted: %s", p, e)


def _mtime(p: Path) -> float:
    try:
        return p.stat().st_mtime
    except OSError:
        return float("inf")


class _ConsoleHandler(logging.StreamHandler):
    """The console: whatever ``sys.stderr`` is when a record is written (a host or a
    test runner may swap and close the stream the handler first saw)."""

    @property
    def stream(self):  # type: ignore[override]
        return sys.stderr

    @stream.setter
    def stream(self, _value) -> None:
        pass


def setup_logging(level: int | str = logging.INFO, settings: LogSettings | None = None, *,
                  console: bool = True) -> Path | None:
    """Console and rotating file logging for the desk; returns the log folder, or None
    when the file could not be opened (said on the console). Calling it again replaces
    the handlers it installed before."""
    global _current_dir
    settings = settings or LogSettings()
    root = logging.getLogger()
    root.setLevel(level if isinstance(level, int) else getattr(logging, level))
    for h in list(root.handlers):
        if getattr(h, "_station_patrol", False):
            root.removeHandler(h)
            h.close()
    fmt = logging.Formatter(FORMAT)
    if console:
        ch = _ConsoleHandler()
        ch.setFormatter(fmt)
        ch._station_patrol = True  # type: ignore[attr-defined]
        root.addHandler(ch)
    folder = Path(settings.dir).expanduser() if settings.dir else paths.log_dir()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fh = RotatingLogHandler(folder / LOG_NAME, keep_days=settings.keep_days,
                                max_bytes=settings.max_bytes, max_files=settings.max_files)
    except OSError as e:
        log.error("no log file in %s (%s); logging to the console only", folder, e)
        _current_dir = None
        return None
    fh.setFormatter(fmt)
    fh._station_patrol = True  # type: ignore[attr-defined]
    root.addHandler(fh)
    _current_dir = folder
    log.debug("logging to %s", folder / LOG_NAME)
    return folder


def stop_logging() -> None:
    """Remove the handlers :func:`setup_logging` installed (and forget their folder)."""
    global _current_dir
    root = logging.getLogger()
    for h in list(root.handlers):
        if getattr(h, "_station_patrol", False):
            root.removeHandler(h)
            h.close()
    _current_dir = None


def current_log_dir() -> Path:
    """The folder :func:`setup_logging` logs to (the default folder before it ran)."""
    return _current_dir if _current_dir is not None else paths.log_dir()
