"""``station-patrol report``: a patrol report without a window.

    station-patrol report --out day.pdf                      the last 24 hours
    station-patrol report --from -2h --out shift.html
    station-patrol report --from 2026-11-21T06:00 --to 2026-11-21T14:00 --out shift.pdf

Times: ISO 8601 (no zone given means UTC), ``now``, or relative to now such as
``-2h``, ``-30m``, ``-90s``, ``-1d``. The format follows the extension of
``--out`` (.pdf or .html). Bad input is named on one line and exits with 2.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import time
from datetime import UTC, datetime
from pathlib import Path

__all__ = ["main", "parse_time"]

_REL = re.compile(r"^(?:now)?\s*([+-])\s*(\d+(?:\.\d+)?)\s*([smhdw])$")
_UNIT_S = {"s": 1.0, "m": 60.0, "h": 3600.0, "d": 86400.0, "w": 604800.0}


def parse_time(text: str, now: float | None = None) -> float:
    """UTC epoch seconds from ISO 8601, ``now`` or ``-2h``-style relative times."""
    now = time.time() if now is None else now
    s = text.strip().lower()
    if not s:
        raise ValueError("empty time")
    if s == "now":
        return now
    m = _REL.match(s)
    if m:
        sign = -1.0 if m.group(1) == "-" else 1.0
        return now + sign * float(m.group(2)) * _UNIT_S[m.group(3)]
    try:
        dt = datetime.fromisoformat(text.strip().replace("Z", "+00:00").replace("z", "+00:00"))
    except ValueError:
        raise ValueError(f"{text!r} is not a time: use ISO 8601 (2026-11-21T06:00), "
                         "'now' or a relative time such as -2h") from None
    if dt.tzinfo is None:
        dt = dt.replace(tzinfo=UTC)
    return dt.timestamp()


def parse_range(frm: str | None, to: str | None, now: float | None = None,
                default_span_s: float = 86400.0) -> tuple[float, float]:
    """``(t0, t1)``; no ``--to`` means now, no ``--from`` means 24 h before ``--to``."""
    now = time.time() if now is None else now
    t1 = parse_time(to, now) if to else now
    t0 = parse_time(frm, now) if frm else t1 - default_span_s
    if t1 <= t0:
        raise ValueError(f"--to ({to or 'now'}) is not after --from ({frm or '-24h'})")
    return t0, t1


class _Parser(argparse.ArgumentParser):
    """Bad arguments: one line on stderr, exit status 2."""

    def error(self, message: str):  # type: ignore[override]
        print(f"{self.prog}: {message}", file=sys.stderr)
        raise SystemExit(2)


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="station-patrol report", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--from", dest="frm", metavar="TIME", help="start (default: 24 h before --to)")
    p.add_argument("--to", metavar="TIME", help="end (default: now)")
    p.add_argument("--out", required=True, metavar="FILE.pdf|FILE.html",
                   help="where to write the report; the extension picks the format")
    p.add_argument("--session", default="latest", metavar="N|latest|all",
                   help="which desk session (a desk run with one robot) to report: its "
                   "number, the latest with data in the range (default), or all mixed")
    p.add_argument("--data-dir", metavar="DIR",
                   help="the desk's data folder (default: the platform's, or "
                        "$STATION_PATROL_DATA_DIR)")
    p.add_argument("--lang", metavar="zh_CN|en", type=_language,
                   help="the report's language (default: the desk's, else the system's)")
    return p


def _language(text: str) -> str:
    from app.core.i18n import check_language

    try:
        return check_language(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def _fail(msg: str) -> int:
    print(f"station-patrol report: {msg}", file=sys.stderr)
    return 2


def join_negative_times(argv: list[str]) -> list[str]:
    """``--from -2h`` would read as an option: pass it as ``--from=-2h``."""
    out: list[str] = []
    i = 0
    while i < len(argv):
        a = argv[i]
        if a in ("--from", "--to") and i + 1 < len(argv) and argv[i + 1].startswith("-") \
                and _REL.match(argv[i + 1].strip().lower()):
            out.append(f"{a}={argv[i + 1]}")
            i += 2
            continue
        out.append(a)
        i += 1
    return out


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    argv = join_negative_times(list(sys.argv[1:] if argv is None else argv))
    try:
        args = parser.parse_args(argv)
    except SystemExit as e:  # argparse has printed its one-line message
        return 0 if e.code == 0 else 2
    out = Path(args.out)
    if out.suffix.lower() not in (".pdf", ".html", ".htm"):
        return _fail(f"cannot tell the format of {args.out!r}: end it in .pdf or .html")
    if not out.parent.exists():
        return _fail(f"the folder {str(out.parent)!r} does not exist")
    try:
        t0, t1 = parse_range(args.frm, args.to)
    except ValueError as e:
        return _fail(str(e))
    from app.core.records import Archive
    from app.core.records.paths import default_archive_path

    path = default_archive_path(args.data_dir)
    if not path.exists():
        return _fail(f"no archive at {path} (record a patrol first, or give --data-dir)")
    # draw figures without a display
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY")
                                                 or os.environ.get("WAYLAND_DISPLAY")):
        os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from PySide6.QtGui import QGuiApplication

    from app.report.data import gather
    from app.report.render import write_report

    _app = QGuiApplication.instance() or QGuiApplication(sys.argv[:1])
    from app.i18n import language, start_language

    if args.lang is not None or language() == "en":  # a desk in Chinese keeps its language
        start_language(_app, args.lang)
    try:
        archive = Archive(path)
    except Exception as e:  # a damaged or foreign file
        return _fail(f"cannot open the archive {path}: {e}")
    from app.core.records.queries import choose_session

    try:
        try:
            rows, which = choose_session(archive, args.session, t0, t1)
        except ValueError as e:
            return _fail(str(e))
        data = gather(rows, t0, t1, source=f"{path}, {which}")
        write_report(data, out)
    except OSError as e:
        return _fail(f"cannot write {args.out}: {e}")
    finally:
        archive.close()
    print(f"{out}: {which}", flush=True)
    print(f"{out}: {len(data.readings)} meter readings, {len(data.alarms)} alarms, "
          f"{sum(s.n for s in data.stats[:1])} telemetry samples, "
          f"{data.distance_m:.1f} m driven", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
