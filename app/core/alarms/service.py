"""Bump tests and calibrations of the gas sensors, and the overdue alarms (no Qt).

IEC 60079-29-2 clause 10 asks for a functional check with test gas (a *bump
test*) at a set interval and a full calibration at a longer one, each recorded
with its date, gas, result and who did it. The record lives in a small JSON
file in the desk's user-data folder, ``gas_service.json`` beside the archive:
the archive's schema is per robot and per session (telemetry, events,
alarms), while a bump test belongs to the sensor and must be recordable with
no robot connected and no archive open. The file is written whole to a
temporary file and renamed, so a crash never leaves half a record.

:func:`service_alarms` turns the record and a :class:`~.setpoints.GasRule`
into two conditions per gas, ``gas.<GAS>.bump_overdue`` and
``gas.<GAS>.calibration_overdue``: active when the last *passed* one is older
than the interval (or there is none). A failed bump test also keeps the alarm
standing (the sensor has not been shown to respond).
"""

from __future__ import annotations

import json
import logging
import os
import time
from dataclasses import asdict, dataclass
from datetime import UTC, datetime
from pathlib import Path

from app.core.alarms.model import Priority
from app.core.alarms.setpoints import GasRule

log = logging.getLogger(__name__)

__all__ = ["KINDS", "SERVICE_FILE", "ServiceAlarm", "ServiceLog", "ServiceRecord",
           "default_service_path", "service_alarms"]

SERVICE_FILE = "gas_service.json"
KINDS = ("bump", "calibration")
DAY = 86400.0


def default_service_path(data_dir: str | Path | None = None) -> Path:
    from app.core.records.paths import default_data_dir  # the archive's folder
    return Path(data_dir if data_dir is not None else default_data_dir()) / SERVICE_FILE


@dataclass(frozen=True)
class ServiceRecord:
    """One bump test or calibration."""

    t: float  # UTC epoch seconds
    kind: str  # "bump" or "calibration"
    gas: str
    result: str  # "pass" or "fail"
    by: str
    note: str = ""

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"kind must be one of {', '.join(KINDS)}, not {self.kind!r}")
        if self.result not in ("pass", "fail"):
            raise ValueError(f"result must be 'pass' or 'fail', not {self.result!r}")
        if not self.gas.strip():
            raise ValueError("gas must name the gas, e.g. CH4")
        if not self.by.strip():
            raise ValueError("who did it (--by) is required")

    @property
    def when(self) -> str:
        return datetime.fromtimestamp(self.t, UTC).strftime("%Y-%m-%d %H:%M UTC")


class ServiceLog:
    """The records of one file; bad entries are counted and skipped."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.records: list[ServiceRecord] = []
        self.skipped = 0
        self.problem = ""
        self._load()

    def _load(self) -> None:
        try:
            data = json.loads(self.path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            return
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
            self.problem = f"{self.path}: cannot be read ({e})"
            log.error("gas service record: %s", self.problem)
            return
        rows = data.get("records", []) if isinstance(data, dict) else []
        for row in rows:
            try:
                self.records.append(ServiceRecord(**row))
            except (TypeError, ValueError) as e:
                self.skipped += 1
                log.warning("gas service record: entry %r skipped (%s)", row, e)
        self.records.sort(key=lambda r: r.t)

    def add(self, rec: ServiceRecord) -> None:
        """Append ``rec`` and write the file (atomically)."""
        if self.problem:
            raise ValueError(f"{self.problem}; fix or move it before recording")
        self.records.append(rec)
        self.records.sort(key=lambda r: r.t)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.path.with_suffix(".json.tmp")
        tmp.write_text(json.dumps({"records": [asdict(r) for r in self.records]}, indent=1),
                       encoding="utf-8")
        os.replace(tmp, self.path)

    def last_pass(self, gas: str, kind: str) -> ServiceRecord | None:
        ok = [r for r in self.records if r.gas.upper() == gas.upper() and r.kind == kind
              and r.result == "pass"]
        return ok[-1] if ok else None

    def last(self, gas: str, kind: str) -> ServiceRecord | None:
        rs = [r for r in self.records if r.gas.upper() == gas.upper() and r.kind == kind]
        return rs[-1] if rs else None


@dataclass(frozen=True)
class ServiceAlarm:
    """One overdue condition, for :meth:`AlarmMonitor.set_condition`."""

    alarm_id: str
    active: bool
    priority: Priority
    text: str
    source: str


def service_alarms(log_: ServiceLog, rules: list[GasRule], now: float | None = None
                   ) -> list[ServiceAlarm]:
    """The overdue conditions of every gas rule at ``now`` (default: the clock)."""
    now = time.time() if now is None else now
    out = []
    for g in rules:
        for kind, days in (("bump", g.bump_test_days), ("calibration", g.calibration_days)):
            what = "bump test" if kind == "bump" else "calibration"
            last_ok = log_.last_pass(g.gas, kind)
            last = log_.last(g.gas, kind)
            if last is not None and last.result == "fail":
                active, text = True, (f"{g.label} {g.gas}: last {what} failed on "
                                      f"{last.when} ({last.by})")
            elif last_ok is None:
                active, text = True, f"{g.label} {g.gas}: no {what} on record"
            else:
                age = (now - last_ok.t) / DAY
                active = age > days
                text = (f"{g.label} {g.gas}: {what} overdue (last {last_ok.when}, "
                        f"every {days:g} days)")
            out.append(ServiceAlarm(f"gas.{g.gas}.{kind}_overdue", active, g.service_priority,
                                    text, g.source or g.channel))
    return out
