"""Why the uncalibrated reader refuses, and whether it was right to: refusals by reason.

    python bench/meter_why.py [--seeds 1,2,3] [--n 40] [--levels clean,field,hard]

Reads the images of ``bench/meter_bench.py --rows tuning`` (the same generator and random
streams, one set per seed; the tuning families, or with ``--families`` some of them or a
former held-out family, never the held-out one) and sorts
every refusal by its deciding reason (numbers masked).  For each reason it prints how
often it decided, and how far the refused reading's best candidate (``Reading.raw_value``:
the value the deciding path came nearest to, e.g. the needle against the profile's arc at
the turn the refused fit came nearest to) lies from the truth, in % of full scale: the
share within 1 and 2 % FS, the median and the largest.  A reason whose candidates are
nearly all within 2 % FS is over-cautious; one whose candidates are often far off is
doing its job.  Refusals with no candidate (no needle, no pivot) are counted apart.

It then prints, for the readings that state an error bound (made against the profile's
angles, returned or refused for low confidence; and the learned keypoints' returned ones),
how the error compares with that bound: how many exceed it and the largest error/bound
ratio, by bound band, and how many refused ones were within 2 % FS.
``--learned-fallback`` lets the learned keypoints read where the classical reader refuses
(as the reader does by default); by default they are off here, so that the classical
paths' own reasons are tallied.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from app.core.meter import load_profile, read_gauge  # noqa: E402
from bench.meter_rows import ROW_IDS, WRONG_PCT_FS, deciding_reason  # noqa: E402
from sim_robot.gauge_scene import LEVELS, render_sample  # noqa: E402
from sim_robot.gauge_styles import (  # noqa: E402
    HELD_OUT_CHOICES,
    HELD_OUT_FAMILY,
    TUNING_FAMILIES,
)

# families it may read: the tuning ones, and former held-out ones (looked at since, usable
# to check that a change generalises); never the held-out family
FAMILIES = (*TUNING_FAMILIES, *(f for f in HELD_OUT_CHOICES if f != HELD_OUT_FAMILY))

BOUND_BANDS = (0.0, 0.35, 0.6, 0.9, 1.5, 3.0, float("inf"))  # % FS


def reason_class(error: str | None) -> str:
    """A refusal's deciding reason with its numbers masked (so that like refusals pool)."""
    return re.sub(r"[-+]?\d+(\.\d+)?", "#", deciding_reason(error))


def collect(seeds: list[int], n: int, levels: list[str], learned: bool,
            families: tuple[str, ...] = TUNING_FAMILIES) -> list[dict]:
    """One record per image: level, reading's value, candidate, error, bound, truth.  With
    the tuning families (the default) these are the images of the tuning rows."""
    out = []
    for seed in seeds:
        for level in levels:
            rng = np.random.default_rng([seed, ROW_IDS["tuning"], LEVELS.index(level)])
            for i in range(n):
                img, truth = render_sample(families[i % len(families)], level, rng)
                prof = load_profile(truth["profile"])
                r = read_gauge(img, prof, learned_fallback=learned)
                fs = truth["full_scale"]
                cand = r.value if r.value is not None else r.raw_value
                out.append({
                    "seed": seed, "level": level, "i": i, "style": truth["style"],
                    "read": r.value is not None, "method": r.method,
                    "reason": None if r.value is not None else reason_class(r.error),
                    "err_fs": None if cand is None else abs(cand - truth["value"]) / fs * 100,
                    "bound_fs": r.error_bound_fs,
                })
    return out


def reason_table(recs: list[dict]) -> str:
    rows = {}
    for r in recs:
        if not r["read"]:
            rows.setdefault(r["reason"], []).append(r["err_fs"])
    lines = [f"{'n':>4} {'cand':>4} {'<=1%':>5} {'<=2%':>5} {'med%FS':>7} {'max%FS':>7}  "
             "deciding reason"]
    for why, errs in sorted(rows.items(), key=lambda kv: -len(kv[1])):
        e = np.array([x for x in errs if x is not None])
        if len(e):
            lines.append(f"{len(errs):4d} {len(e):4d} {np.mean(e <= 1.0) * 100:4.0f}% "
                         f"{np.mean(e <= WRONG_PCT_FS) * 100:4.0f}% {np.median(e):7.2f} "
                         f"{e.max():7.2f}  {why}")
        else:
            lines.append(f"{len(errs):4d} {0:4d} {'-':>5} {'-':>5} {'-':>7} {'-':>7}  {why}")
    return "\n".join(lines)


def bound_table(recs: list[dict]) -> str:
    lines = ["  bound %FS     n  read  beyond  max err/bound  refused <=2%FS"]
    for lo, hi in zip(BOUND_BANDS[:-1], BOUND_BANDS[1:], strict=True):
        sel = [r for r in recs if r["bound_fs"] is not None and r["err_fs"] is not None
               and lo <= r["bound_fs"] < hi]
        if not sel:
            continue
        ratio = [r["err_fs"] / max(r["bound_fs"], 1e-9) for r in sel]
        refused = [r for r in sel if not r["read"]]
        ok = sum(r["err_fs"] <= WRONG_PCT_FS for r in refused)
        lines.append(f"  {lo:4.2f}-{hi:<5.2f} {len(sel):5d} {sum(r['read'] for r in sel):5d}"
                     f" {sum(x > 1.0 for x in ratio):7d} {max(ratio):14.2f}"
                     f"  {ok:3d} of {len(refused)}")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--n", type=int, default=40, help="images per level and seed")
    ap.add_argument("--levels", default="clean,field,hard")
    ap.add_argument("--learned-fallback", action=argparse.BooleanOptionalAction,
                    default=False, help="let the learned keypoints read where the classical "
                    "reader refuses (off here by default)")
    ap.add_argument("--families", default="",
                    help=f"families to read (default the tuning ones; of {', '.join(FAMILIES)};"
                    f" never the held-out {HELD_OUT_FAMILY})")
    args = ap.parse_args(argv)
    fams = tuple(args.families.split(",")) if args.families else TUNING_FAMILIES
    if any(f not in FAMILIES for f in fams):
        ap.error(f"families are {', '.join(FAMILIES)} (never the held-out {HELD_OUT_FAMILY})")
    levels = args.levels.split(",")
    if any(lv not in LEVELS for lv in levels):
        ap.error(f"levels are {', '.join(LEVELS)}")
    cv2.setNumThreads(1)
    seeds = [int(s) for s in args.seeds.split(",")]
    recs = collect(seeds, args.n, levels, args.learned_fallback, fams)
    which = "tuning families" if fams == TUNING_FAMILIES else ", ".join(fams)
    print(f"meter why: {which}, seeds {args.seeds}, n={args.n} per level and seed, "
          f"learned fallback {'on' if args.learned_fallback else 'off'}; load average "
          f"{os.getloadavg()[0]:.1f}")
    for level in [*levels, "all"]:
        sel = [r for r in recs if level in ("all", r["level"])]
        read = [r for r in sel if r["read"]]
        wrong = sum(r["err_fs"] > WRONG_PCT_FS for r in read)
        print(f"\n{level}: {len(sel)} images, read {len(read)} "
              f"({100.0 * len(read) / max(len(sel), 1):.1f} %), wrong {wrong}; refusals by "
              "deciding reason, candidate's error in % FS:")
        print(reason_table(sel))
    for method in ("profile-angles", "keypoints"):
        sel = [r for r in recs if (r["method"] == "keypoints") == (method == "keypoints")]
        print(f"\n{method} readings (returned, or refused for low confidence), error against "
              "the bound they state:")
        print(bound_table(sel))
    return 0


if __name__ == "__main__":
    sys.exit(main())
