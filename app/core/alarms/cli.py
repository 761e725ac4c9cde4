"""``station-patrol alarms``: the alarm rules without the window.

    station-patrol alarms                    list the rules in force (shipped defaults)
    station-patrol alarms --file site.toml   the defaults overridden by site.toml
    station-patrol alarms --check site.toml  only check the file; exit 2 if anything is wrong
    station-patrol alarms --dump             print the rules in force as TOML

Gas sensor service record (the user-data folder's gas_service.json):

    python -m app.core.alarms bump-test   --gas CH4 --result pass --by NAME [--note ..]
    python -m app.core.alarms calibration --gas CH4 --result pass --by NAME [--note ..]
    python -m app.core.alarms service [--gas CH4]     list the records and what is due

Problems are printed one per line, naming the file, the key and what is wrong.
"""

from __future__ import annotations

import argparse
import sys
from typing import TextIO

from app.core.alarms.config import AlarmConfig, dump_alarm_config, load_alarm_config
from app.core.alarms.service import ServiceLog, ServiceRecord, default_service_path, service_alarms

__all__ = ["SERVICE_COMMANDS", "main", "rules_table", "service_main"]

SERVICE_COMMANDS = ("bump-test", "calibration", "service")


def rules_table(cfg: AlarmConfig) -> list[str]:
    """The rules as aligned text lines."""
    lines = [f"{'point':<20} {'kind':<6} {'low':>8} {'high':>8} {'deadband':>8} "
             f"{'on s':>5} {'off s':>5}  priority"]

    def num(v):
        return "" if v is None else f"{v:g}"

    for r in cfg.limits:
        lines.append(f"{r.channel:<20} {'limit':<6} {num(r.low):>8} {num(r.high):>8} "
                     f"{num(r.deadband):>8} {num(r.on_delay_s):>5} {num(r.off_delay_s):>5}  "
                     f"{r.priority.name}")
    for r in cfg.rates:
        lines.append(f"{r.channel:<20} {'rate':<6} {'':>8} {num(r.rise_per_min):>8} "
                     f"{num(r.deadband):>8} {num(r.on_delay_s):>5} {num(r.off_delay_s):>5}  "
                     f"{r.priority.name}  ({r.unit or 'units'}/min over {r.window_s:g} s)")
    for sp in cfg.setpoints:
        hi, lo = (sp.value, None) if sp.direction == "rising" else (None, sp.value)
        lines.append(f"{sp.key:<20} {'setpt':<6} {num(lo):>8} {num(hi):>8} "
                     f"{num(sp.deadband):>8} {num(sp.on_delay_s):>5} {num(sp.off_delay_s):>5}  "
                     f"{sp.priority.name}" + ("  latching" if sp.latching else "")
                     + (f"  stage {sp.stage}" if sp.stage else ""))
    for g in cfg.gas:
        lines.append(f"{g.channel + '.fault':<20} {'gas':<6} {num(g.fault_below):>8} {'':>8} "
                     f"{'':>8} {'':>5} {'':>5}  {g.fault_priority.name}  ({g.gas}: fault below "
                     f"{g.fault_below:g} {g.unit} or stuck {g.stuck_s:g} s; bump test every "
                     f"{g.bump_test_days:g} d, calibration every {g.calibration_days:g} d)")
    for r in cfg.stale:
        lines.append(f"{r.channel:<20} {'stale':<6} {'':>8} {num(r.after_s):>8} {'':>8} "
                     f"{'':>5} {'':>5}  {r.priority.name}  (silent for more than "
                     f"{r.after_s:g} s)")
    for name, (pri, text) in cfg.flags.items():
        lines.append(f"{'flag.' + name:<20} {'flag':<6} {'':>8} {'':>8} {'':>8} {'':>5} "
                     f"{'':>5}  {pri.name}  {text}")
    for c in cfg.conditions:
        lines.append(f"{c.alarm_id:<20} {'cond':<6} {'':>8} {'':>8} {'':>8} {'':>5} "
                     f"{'':>5}  {c.priority.name}  {c.text}")
    lines.append(f"flood guard: more than {cfg.flood_per_minute} alarms in "
                 f"{cfg.flood_window_s:g} s; longest shelving {cfg.max_shelve_s:g} s")
    return lines


def main(argv: list[str] | None = None, out: TextIO | None = None) -> int:
    """The command; ``out`` (default: standard output) receives the listing."""
    out = out or sys.stdout
    if argv is None:
        argv = sys.argv[1:]
    if argv[:1] and argv[0] in SERVICE_COMMANDS:
        return service_main(argv, out)
    p = argparse.ArgumentParser(prog="station-patrol alarms", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--file", metavar="FILE.toml", help="rules overriding the shipped defaults")
    p.add_argument("--check", metavar="FILE.toml", help="only check this file")
    p.add_argument("--dump", action="store_true", help="print the rules in force as TOML")
    args = p.parse_args(argv)
    path = args.check or args.file
    cfg, problems = load_alarm_config(path)
    for line in problems:
        print(f"station-patrol alarms: {line}", file=sys.stderr)
    if args.check:
        if not problems:
            print(f"{args.check}: ok ({len(cfg.limits)} limits, {len(cfg.rates)} rate, "
                  f"{len(cfg.stale)} stale, {len(cfg.flags)} flag, "
                  f"{len(cfg.conditions)} condition rules)", file=out)
        return 2 if problems else 0
    print(dump_alarm_config(cfg) if args.dump else "\n".join(rules_table(cfg)), file=out)
    return 2 if problems else 0


def service_main(argv: list[str], out: TextIO | None = None,
                 now: float | None = None) -> int:
    """Record a bump test or calibration, or list the record; exit 2 on bad input."""
    import time
    out = out or sys.stdout
    p = argparse.ArgumentParser(prog="python -m app.core.alarms",
                                description="gas sensor bump tests and calibrations")
    sub = p.add_subparsers(dest="cmd", required=True)
    for name in ("bump-test", "calibration"):
        q = sub.add_parser(name, help=f"record a {name.replace('-', ' ')}")
        q.add_argument("--gas", required=True, help="the gas, e.g. CH4")
        q.add_argument("--result", required=True, choices=("pass", "fail"))
        q.add_argument("--by", required=True, help="who did it")
        q.add_argument("--note", default="")
    q = sub.add_parser("service", help="list the record and what is due")
    q.add_argument("--gas", default=None)
    for q in sub.choices.values():
        q.add_argument("--file", default=None, help="the record file (default: the "
                       "user-data folder's gas_service.json)")
        q.add_argument("--alarms", default=None, metavar="FILE.toml",
                       help="alarm rules with the intervals (default: the shipped ones)")
    args = p.parse_args(argv)
    path = args.file or default_service_path()
    book = ServiceLog(path)
    now = time.time() if now is None else now
    if args.cmd != "service":
        kind = "bump" if args.cmd == "bump-test" else "calibration"
        try:
            rec = ServiceRecord(now, kind, args.gas.strip().upper(), args.result, args.by,
                                args.note)
            book.add(rec)
        except (ValueError, OSError) as e:
            print(f"python -m app.core.alarms {args.cmd}: {e}", file=sys.stderr)
            return 2
        print(f"{path}: {args.cmd} of {rec.gas} recorded ({rec.result}, by {rec.by}, "
              f"{rec.when})", file=out)
        return 0
    if book.problem:
        print(book.problem, file=sys.stderr)
    rows = [r for r in book.records if args.gas is None or r.gas.upper() == args.gas.upper()]
    print(f"{'when':<20} {'kind':<12} {'gas':<6} {'result':<6} by", file=out)
    for r in rows:
        print(f"{r.when:<20} {r.kind:<12} {r.gas:<6} {r.result:<6} {r.by}"
              + (f"  ({r.note})" if r.note else ""), file=out)
    cfg, problems = load_alarm_config(args.alarms)
    for line in problems:
        print(f"python -m app.core.alarms: {line}", file=sys.stderr)
    for a in service_alarms(book, cfg.gas, now):
        if args.gas is None or a.alarm_id.split(".")[1].upper() == args.gas.upper():
            print(f"{'DUE ' if a.active else 'ok  '} {a.text if a.active else a.alarm_id}",
                  file=out)
    return 2 if book.problem or problems else 0


if __name__ == "__main__":
    sys.exit(main())
