"""``station-patrol alarms``: the alarm rules without the window.

    station-patrol alarms                    list the rules in force (shipped defaults)
    station-patrol alarms --file site.toml   the defaults overridden by site.toml
    station-patrol alarms --check site.toml  only check the file; exit 2 if anything is wrong
    station-patrol alarms --dump             print the rules in force as TOML

Problems are printed one per line, naming the file, the key and what is wrong.
"""

from __future__ import annotations

import argparse
import sys
from typing import TextIO

from app.core.alarms.config import AlarmConfig, dump_alarm_config, load_alarm_config

__all__ = ["main", "rules_table"]


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


if __name__ == "__main__":
    sys.exit(main())
