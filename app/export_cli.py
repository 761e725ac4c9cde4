"""``station-patrol export --mcap OUT.mcap``: a session of the archive as an MCAP file.

    station-patrol export --mcap shift.mcap                  the latest session, whole
    station-patrol export --mcap day.mcap --session 3 --from 2026-11-21T06:00 --to now
    station-patrol export --mcap all.mcap --session all --archive /data/archive.sqlite3
    station-patrol export --mcap r2.mcap --robot 10.0.0.12     the latest session of that robot

Topics and schemas: :mod:`app.core.records.mcap_export` and docs/interop.md. A line on
stderr every 5 % of the rows shows progress; bad input (no archive, an unknown
session, an empty range) is one line on stderr and exit status 2.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

from app.report.cli import join_negative_times, parse_time


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # type: ignore[override]
        print(f"{self.prog}: {message}", file=sys.stderr)
        raise SystemExit(2)


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="station-patrol export", description=__doc__,
                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--mcap", required=True, metavar="OUT.mcap", help="the file to write")
    p.add_argument("--from", dest="frm", metavar="TIME",
                   help="start (ISO 8601, 'now', -2h; default: the session's first row)")
    p.add_argument("--to", metavar="TIME", help="end (default: the session's last row)")
    p.add_argument("--session", default="latest", metavar="N|latest|all",
                   help="which desk session: its number, the latest with telemetry in the "
                   "range (default), or all mixed")
    p.add_argument("--robot", metavar="ADDRESS", help="with --session latest: the latest "
                   "session of the robot whose address contains ADDRESS")
    p.add_argument("--archive", metavar="PATH", help="the archive file (default: "
                   "archive.sqlite3 in the data folder)")
    p.add_argument("--data-dir", metavar="DIR", help="the desk's data folder (default: the "
                   "platform's, or $STATION_PATROL_DATA_DIR)")
    return p


def _fail(msg: str) -> int:
    print(f"station-patrol export: {msg}", file=sys.stderr)
    return 2


def main(argv: list[str] | None = None) -> int:
    argv = join_negative_times(list(sys.argv[1:] if argv is None else argv))
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as e:
        return 0 if e.code == 0 else 2
    now = time.time()
    try:
        t0 = parse_time(args.frm, now) if args.frm else -math.inf
        t1 = parse_time(args.to, now) if args.to else math.inf
    except ValueError as e:
        return _fail(str(e))
    if t1 <= t0:
        return _fail(f"--to ({args.to}) is not after --from ({args.frm})")
    from app.core.records import Archive, ArchiveError, default_archive_path
    from app.core.records.mcap_export import ExportError, export_mcap
    from app.core.records.queries import choose_session

    path = Path(args.archive) if args.archive else default_archive_path(args.data_dir)
    if not path.is_file():
        return _fail(f"no archive at {path} (record a patrol first, or give --archive)")
    try:
        archive = Archive(path)
    except (ArchiveError, OSError) as e:
        return _fail(f"cannot open the archive {path}: {e}")
    try:
        which_session: str | int = args.session
        if args.robot:
            if args.session != "latest":
                return _fail("--robot picks the latest session of a robot: give it "
                             "without --session")
            mine = [s for s in archive.sessions() if args.robot in s["robot"]
                    and s["telemetry"] > 0]
            if not mine:
                known = sorted({s["robot"] for s in archive.sessions() if s["robot"]})
                return _fail(f"no session with a robot matching {args.robot!r} "
                             f"(robots: {', '.join(known) or 'none recorded'})")
            which_session = mine[-1]["id"]
        try:
            rows, which = choose_session(archive, which_session, t0, t1)
        except ValueError as e:
            return _fail(str(e))
        print(f"station-patrol export: {path}, {which}", file=sys.stderr, flush=True)
        started = time.monotonic()

        def progress(f: float) -> None:
            print(f"station-patrol export: {f * 100:3.0f} % ({time.monotonic() - started:.1f} s)",
                  file=sys.stderr, flush=True)

        try:
            result = export_mcap(rows, args.mcap, t0, t1, progress=progress)
        except ExportError as e:
            return _fail(f"{e} ({which})")
    finally:
        archive.close()
    print(f"{args.mcap}: {result.messages} messages on {len(result.topics)} topics in "
          f"{time.monotonic() - started:.1f} s", flush=True)
    for topic, s in result.topics.items():
        print(f"  {topic:<18} {s.schema:<28} {s.count:>8}", flush=True)
    return 0
