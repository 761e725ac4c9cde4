"""Are the calibrated reader's refusals doing their job?  (issue 11, section 1)

A refusal for low confidence still carries the reading the reader would have given
(``Reading.raw_value``).  For every such refusal on TUNING data (the ``cal-same`` row's
frames and the stress cases of ``bench/meter_cal_stress.py``; the held-out family is never
drawn here), this compares that would-be reading with the truth the bench knows, and groups
the refusals by the score that decided them (the lowest).  A class whose would-be readings
are nearly always right is over-cautious; one whose would-be readings are often wrong by
more than 2 % FS is doing its job.  Refusals without a would-be reading (no needle found,
outside the scale, registration) are counted by their reason.

    PYTHONPATH=$PWD python bench/meter_cal_why.py --n 100 --seeds 1,2,3 [--stress-n 40]

Per class: refusals, would-be readings within 1 % / 2 % FS and beyond 2 % FS (the ones the
refusal saved), the median would-be error, and how many of the class had another score
below 0.5 as well (the refusal would stand without this score).  With ``-v`` each
refusal's line.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections import defaultdict
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import app.core.meter as meter  # noqa: E402
from bench.meter_bench_calibrated import calibrated_profile  # noqa: E402
from bench.meter_cal_stress import CASES, sample  # noqa: E402
from bench.meter_rows import ROW_IDS, WRONG_PCT_FS, timed_read  # noqa: E402
from sim_robot.gauge_scene import render_sample  # noqa: E402
from sim_robot.gauge_styles import TUNING_FAMILIES  # noqa: E402

ALSO_LOW = 0.5  # another score this low would refuse the reading by itself


def cal_same_cases(n: int, seed: int):
    """The ``cal-same`` tuning row's frames (as ``run_cal_same`` draws them)."""
    rng = np.random.default_rng([seed, ROW_IDS["cal-same"], 0])
    for i in range(n):
        fam = TUNING_FAMILIES[i % len(TUNING_FAMILIES)]
        img, truth = render_sample(fam, "field", rng)
        yield f"cal-same s{seed} #{i} {truth['style']}", img, truth, calibrated_profile(truth, rng)


def stress_cases(case: str, n: int, seed: int):
    rng = np.random.default_rng([seed, 31, CASES.index(case)])
    for i in range(n):
        img, truth, prof = sample(case, i, rng)
        yield f"{case} s{seed} #{i} {truth['style']}", img, truth, prof


def refusal_class(r) -> tuple[str, float | None]:
    """(class, would-be value or None) of a refused reading."""
    raw = getattr(r, "raw_value", None)
    scores = getattr(r, "scores", None) or {}
    if raw is None or not scores:
        return "hard: " + (r.error or "?").split(";")[0][:60], None
    worst = min(scores, key=scores.get)
    return worst, float(raw)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=100, help="cal-same frames per seed")
    ap.add_argument("--stress-n", type=int, default=40, help="frames per stress case and seed")
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--cases", default=",".join(c for c in CASES if c != "base"),
                    help="stress cases ('' for none)")
    ap.add_argument("--cv-threads", type=int, default=1)
    ap.add_argument("-v", "--verbose", action="store_true", help="one line per refusal")
    args = ap.parse_args(argv)
    cv2.setNumThreads(args.cv_threads)
    seeds = [int(s) for s in args.seeds.split(",") if s]
    cases = [c for c in args.cases.split(",") if c]
    bad = [c for c in cases if c not in CASES]
    if bad:
        ap.error(f"unknown case(s) {', '.join(bad)}")
    classes: dict[str, list] = defaultdict(list)  # class -> [(err or None, also_low, label)]
    n_read = n_all = n_wrong = 0
    sources = [("cal-same", s) for s in seeds] + [(c, s) for c in cases for s in seeds]
    for src, seed in sources:
        gen = (cal_same_cases(args.n, seed) if src == "cal-same"
               else stress_cases(src, args.stress_n, seed))
        for label, img, truth, prof in gen:
            r, _ = timed_read(img, meter.load_profile(prof))
            n_all += 1
            fs = truth["full_scale"]
            if r.value is not None:
                n_read += 1
                n_wrong += abs(r.value - truth["value"]) / fs * 100.0 > WRONG_PCT_FS
                continue
            cls, raw = refusal_class(r)
            err = None if raw is None else abs(raw - truth["value"]) / fs * 100.0
            sc = r.scores or {}
            also = sum(v < ALSO_LOW for k, v in sc.items() if k != cls) > 0
            classes[cls].append((err, also, label, {k: round(v, 2) for k, v in sc.items()
                                                    if v < 0.999}))
            if args.verbose:
                e = "-" if err is None else f"{err:6.2f}"
                print(f"  {cls:22} err {e:>6} % FS  {label}  {r.error}  {classes[cls][-1][3]}")
    print(f"calibrated refusals on tuning data: seeds {args.seeds}, cal-same n={args.n}, "
          f"stress {','.join(cases) or '-'} n={args.stress_n}; load {os.getloadavg()[0]:.1f}")
    print(f"frames {n_all}, read {n_read} ({100.0 * n_read / max(n_all, 1):.1f} %), "
          f"confident wrong {n_wrong}")
    print(f"{'refusal class':34} {'n':>4} {'<=1%':>5} {'<=2%':>5} {'>2%':>5} "
          f"{'median%':>8} {'also low':>8}")
    for cls, rows in sorted(classes.items(), key=lambda kv: -len(kv[1])):
        errs = np.array([e for e, *_ in rows if e is not None])
        also = sum(a for _, a, *_ in rows)
        if len(errs):
            print(f"{cls[:34]:34} {len(rows):4d} {int((errs <= 1).sum()):5d} "
                  f"{int((errs <= 2).sum()):5d} {int((errs > 2).sum()):5d} "
                  f"{float(np.median(errs)):8.2f} {also:8d}")
        else:
            print(f"{cls[:34]:34} {len(rows):4d} {'-':>5} {'-':>5} {'-':>5} {'-':>8} {also:8d}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
