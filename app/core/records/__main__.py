"""Query the patrol archive from the command line (no window).

    python -m app.core.records info
    python -m app.core.records series temp_c --from -2h --points 50
    python -m app.core.records export --channels gas_lel_pct,temp_c --from 2026-11-21T08:00 \\
        --to 2026-11-21T12:00 --out gas.csv
    python -m app.core.records events --kind patrol_status --from -1d
    python -m app.core.records alarms | commands | meters [--from ... --to ...]
    python -m app.core.records check
    python -m app.core.records prune --days 30 [--export DIR]

Everything that reads rows (series, export, events, alarms, commands, meters) reads
one session (a desk run with one robot): ``--session latest`` (default: the newest
with telemetry in the range), ``--session N``, or ``--session all`` (every session
mixed, said so). The session used is named on stderr ("session 7 — robot ...");
``info`` lists the sessions. Without ``--from``/``--to`` the range is the session's.

``--archive FILE`` or ``--data-dir DIR`` choose the file (default: the desk's data folder,
``$STATION_PATROL_DATA_DIR`` or the platform's user-data folder). Times are ISO 8601 (UTC
unless they carry an offset), epoch seconds, or relative to now: ``-90s``, ``-15m``,
``-2h``, ``-1d`` (``--from -2h`` works as written). Output is CSV (series, tables) or
JSON lines (events). A channel the archive does not hold is an error that names the
channels it does hold (exit 2), never an empty answer.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import re
import sys
import time
from datetime import UTC, datetime
from pathlib import Path

from app.core.records.archive import Archive, ArchiveError, _iso, fmt_number
from app.core.records.paths import default_archive_path
from app.core.records.queries import choose_session, describe_session

READS_ROWS = ("series", "export", "events", "alarms", "commands", "meters")

_REL = re.compile(r"^-(\d+(?:\.\d+)?)([smhd])$")
_UNIT_S = {"s": 1, "m": 60, "h": 3600, "d": 86400}


def parse_time(text: str) -> float:
    """ISO 8601 (UTC when no offset), epoch seconds, or ``-<n>[smhd]`` before now."""
    text = text.strip()
    m = _REL.match(text)
    if m:
        return time.time() - float(m.group(1)) * _UNIT_S[m.group(2)]
    try:
        return float(text)
    except ValueError:
        pass
    try:
        dt = datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"not a time: {text!r} (use ISO 8601, epoch seconds or -2h)") from None
    if dt.tzinfo is None:
        dt = dt.replace(tzinfo=UTC)
    return dt.timestamp()


def join_relative_times(argv: list[str]) -> list[str]:
    """``--from -2h`` would read as an option to argparse: pass it as ``--from=-2h``."""
    out: list[str] = []
    i = 0
    while i < len(argv):
        a = argv[i]
        if a in ("--from", "--to") and i + 1 < len(argv) and _REL.match(argv[i + 1].strip()):
            out.append(f"{a}={argv[i + 1]}")
            i += 2
            continue
        out.append(a)
        i += 1
    return out


def unknown_channels(asked: list[str], known: list[str]) -> str | None:
    """The error for channels the archive does not hold, or None when all are known."""
    missing = [c for c in asked if c not in known]
    if not missing:
        return None
    what = ", ".join(repr(c) for c in missing)
    held = ", ".join(known) if known else "none yet (the archive holds no telemetry)"
    return f"unknown channel {what}; the archive's channels: {held}"


def _table(rows: list[dict]) -> None:
    if not rows:
        return
    w = csv.writer(sys.stdout)
    cols = list(rows[0])
    w.writerow(["time_utc", *cols])
    for r in rows:
        w.writerow([_iso(r["t"]), *(json.dumps(r[c]) if isinstance(r[c], dict) else r[c]
                                    for c in cols)])


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m app.core.records", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--archive", metavar="FILE", help="the archive file")
    p.add_argument("--data-dir", metavar="DIR", help="the desk's data folder")
    sub = p.add_subparsers(dest="cmd", required=True)
    for name in ("info", "check"):
        sub.add_parser(name)
    s = sub.add_parser("series", help="one channel, down-sampled (CSV)")
    s.add_argument("channel")
    s.add_argument("--points", type=int, default=2000)
    e = sub.add_parser("export", help="raw telemetry rows to CSV")
    e.add_argument("--channels", help="comma-separated (default: all)")
    e.add_argument("--out", required=True)
    ev = sub.add_parser("events", help="events as JSON lines")
    ev.add_argument("--kind", action="append", help="only this kind (repeatable)")
    for name in ("alarms", "commands", "meters"):
        q = sub.add_parser(name)
        if name == "meters":
            q.add_argument("--raw", action="store_true", help="also every frame's reading")
    pr = sub.add_parser("prune", help="delete rows older than N days")
    pr.add_argument("--days", type=float, required=True)
    pr.add_argument("--export", metavar="DIR", help="write them to CSV files first")
    for name in READS_ROWS:
        q = sub.choices[name]
        q.add_argument("--from", dest="t0", type=parse_time,
                       help="start (default: the session's first row)")
        q.add_argument("--to", dest="t1", type=parse_time,
                       help="end (default: the session's last row)")
        q.add_argument("--session", default="latest", metavar="N|latest|all",
                       help="which session's rows: its number, the newest with telemetry "
                            "in the range (default), or all mixed")
    args = p.parse_args(join_relative_times(list(sys.argv[1:] if argv is None else argv)))

    path = Path(args.archive) if args.archive else default_archive_path(args.data_dir)
    if not path.exists():
        print(f"no archive at {path}", file=sys.stderr)
        return 1
    try:
        a = Archive(path)
    except ArchiveError as err:
        print(f"archive: {err}", file=sys.stderr)
        return 1
    try:
        rows, rng = a, a.time_range()
        t0, t1 = getattr(args, "t0", None), getattr(args, "t1", None)
        if args.cmd in READS_ROWS:
            try:
                rows, which = choose_session(a, args.session,
                                             -math.inf if t0 is None else t0,
                                             math.inf if t1 is None else t1)
            except ValueError as err:
                print(err, file=sys.stderr)
                return 2
            print(f"reading {which}", file=sys.stderr)
            rng = rows.time_range()
        t0 = t0 if t0 is not None else (rng[0] if rng else 0.0)
        t1 = t1 if t1 is not None else (rng[1] if rng else 0.0)
        if args.cmd == "info":
            print(f"archive: {path} ({path.stat().st_size / 1e6:.1f} MB)")
            print("time range: " + (f"{_iso(rng[0])} .. {_iso(rng[1])}" if rng else "empty"))
            for table, n in a.counts().items():
                print(f"  {table:<17} {n}")
            print("channels: " + ", ".join(a.channels()))
            for sess in a.sessions():
                print(f"  {describe_session(sess)}: {sess['telemetry']} telemetry rows")
        elif args.cmd == "check":
            result = a.integrity_check()
            print(f"integrity_check: {result}")
            return 0 if result == "ok" else 1
        elif args.cmd == "series":
            err = unknown_channels([args.channel], a.channels())
            if err:
                print(err, file=sys.stderr)
                return 2
            sr = rows.series(args.channel, t0, t1, max_points=args.points)
            w = csv.writer(sys.stdout)
            w.writerow(["time_utc", "t", "mean", "min", "max"])
            for i in range(len(sr)):
                w.writerow([_iso(sr.t[i]), f"{sr.t[i]:.3f}", fmt_number(sr.mean[i]),
                            fmt_number(sr.vmin[i]), fmt_number(sr.vmax[i])])
            print(f"{len(sr)} points from {sr.source}", file=sys.stderr)
        elif args.cmd == "export":
            chans = [c.strip() for c in args.channels.split(",")] if args.channels else None
            err = unknown_channels(chans or [], a.channels())
            if err:
                print(err, file=sys.stderr)
                return 2
            n = rows.export_csv(chans, t0, t1, args.out)
            print(f"{n} rows written to {args.out}", file=sys.stderr)
        elif args.cmd == "events":
            for ev_ in rows.events(t0, t1, kinds=args.kind):
                print(json.dumps({"time_utc": _iso(ev_["t"]), **ev_}, default=str))
        elif args.cmd == "alarms":
            _table(rows.alarm_transitions(t0, t1))
        elif args.cmd == "commands":
            _table(rows.commands(t0, t1))
        elif args.cmd == "meters":
            _table(rows.meter_readings(t0, t1, fused_only=not args.raw))
        elif args.cmd == "prune":
            before = time.time() - args.days * 86400.0
            if not a.prune(before, export_dir=args.export).wait(3600):
                print("pruning did not finish within an hour", file=sys.stderr)
                return 1
            st = a.stats()
            print(f"pruned rows older than {_iso(before)}: {st['pruned']}; "
                  f"exported: {st['exported']}")
    finally:
        a.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
