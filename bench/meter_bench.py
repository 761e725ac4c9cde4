"""Pointer-gauge reading benchmark: clean / field / hard levels and the paper's Table 2.

    python bench/meter_bench.py [--n 200] [--seed 1] [--steps] [--rows ROWS] [--family F]

``--rows`` picks what is run (default: all, in this order):

* ``stock``   issue 3's levels on ``sim_robot/gauge_render.py`` (described below);
* ``table2``  the paper's Table 2 of seed 000;
* ``tuning``  issue 11's uncalibrated rows clean / field / hard on the styled generator's
  tuning families (``sim_robot/gauge_styles.py``; ``--family`` narrows them);
* ``heldout`` the same rows on the held-out family, which is kept out of all tuning
  (``foundry``; ``--heldout atlas`` runs them on the former held-out family instead, to
  re-run earlier figures);
* ``cal-same`` calibrated profiles (pivot and end marks with click noise), same image
  coordinates, field-like frames; ``cal-ref`` calibrated with a reference frame, the robot
  re-visiting the station's inspection points (``bench/meter_bench_calibrated.py``);
  ``--split tuning|heldout`` runs these two on one split only (default both).

The issue 11 rows are described in ``bench/meter_rows.py``; each prints the command that
reproduces it and its goal.  ``--levels`` narrows the stock and uncalibrated rows.

Per level it prints: readable %, mean absolute error and p95 error in % of full scale (over
readable images), the share of confident (returned) readings more than 2 % FS wrong, and
milliseconds per image (reading only, not rendering; wall clock, and the process's CPU
time, which a busy machine inflates less), timed after one warm-up reading.  ``--steps``
adds the CPU time of each reader step per image.  Figures are what they are; the goals
of issue 3 are printed beside them.
"""

from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import app.core.meter as meter_pkg  # noqa: E402
from app.core.meter import load_profile, read_gauge  # noqa: E402
from app.core.meter.interpolate import eq21_reading  # noqa: E402
from app.core.paths import resource  # noqa: E402
from bench import meter_rows  # noqa: E402
from bench.meter_bench_calibrated import calibrated_rows  # noqa: E402
from bench.meter_rows import HEADER, WRONG_PCT_FS, uncalibrated_rows  # noqa: E402
from sim_robot.gauge_render import (  # noqa: E402
    PAPER_TABLE1,
    STOCK_SPECS,
    random_spec,
    render_dial,
    render_view,
)
from sim_robot.gauge_styles import (  # noqa: E402
    HELD_OUT_CHOICES,
    HELD_OUT_FAMILY,
    TUNING_FAMILIES,
)

GOALS = {
    "clean": (100.0, 0.10, 0.0, 5.0),
    "field": (98.0, 0.30, 0.0, 10.0),
    "hard": (95.0, 0.50, 0.5, 30.0),
}
ROOT = Path(__file__).resolve().parents[1]


def _spec(rng):
    if rng.random() < 0.35:
        return STOCK_SPECS[int(rng.integers(0, len(STOCK_SPECS)))]
    return random_spec(rng)


def _value(spec, rng):
    return float(rng.uniform(spec.min_value, spec.max_value))


def make_case(level: str, rng: np.random.Generator):
    spec = _spec(rng)
    v = _value(spec, rng)
    if level == "clean":
        return spec, v, render_dial(spec, v, 300)
    if level == "field":
        img, _ = render_view(
            spec, v, frame_size=(320, 320), fill=float(rng.uniform(0.82, 0.95)),
            tilt_deg=float(rng.uniform(0, 20)), tilt_axis_deg=float(rng.uniform(0, 180)),
            roll_deg=float(rng.uniform(-10, 10)), glare=float(rng.uniform(0.0, 0.5)),
            noise_sigma=float(rng.uniform(1, 5)), blur_px=float(rng.uniform(0, 0.8)),
            jpeg_quality=int(rng.integers(60, 95)), rng=rng)
        return spec, v, img
    img, _ = render_view(
        spec, v, frame_size=(640, 480), fill=float(rng.uniform(0.4, 0.8)),
        tilt_deg=float(rng.uniform(0, 35)), tilt_axis_deg=float(rng.uniform(0, 180)),
        roll_deg=float(rng.uniform(-15, 15)), glare=float(rng.uniform(0.3, 0.7)),
        glare_on_pointer=True, noise_sigma=float(rng.uniform(2, 7)),
        motion_blur_px=float(rng.uniform(0, 4)), jpeg_quality=int(rng.integers(50, 90)), rng=rng)
    return spec, v, img


STEPS = ("find_crop_rim", "_full_search", "_affine_pass", "read_normalised", "dark_features",
         "otsu_threshold", "segment_pointer", "zhang_suen", "robust_pointer_line", "fit_circle",
         "find_scale", "_finish", "read_by_angles")


class StepTimer:
    """CPU time per reader step (``--steps``): wraps the step functions the reader calls, by
    name, for this process only.  Nested steps are counted inside their parents as well."""

    def __init__(self, names=STEPS):
        from app.core.meter import angles, pointer, reader, search

        self.total: dict[str, float] = {}
        self.calls: dict[str, int] = {}
        wrapped: dict[str, object] = {}
        # a step is wrapped where it is called from: in every module that holds it by name
        for mod in (reader, search, pointer, angles):
            for name in names:
                if hasattr(mod, name):
                    f = getattr(mod, name)
                    key = getattr(f, "__name__", name)
                    if key not in wrapped:
                        wrapped[key] = self._wrap(name, f)
                    setattr(mod, name, wrapped[key])

    def _wrap(self, name, f):
        def timed(*a, **k):
            t0 = time.process_time()
            try:
                return f(*a, **k)
            finally:
                self.total[name] = self.total.get(name, 0.0) + time.process_time() - t0
                self.calls[name] = self.calls.get(name, 0) + 1
        return timed

    def reset(self) -> None:
        self.total.clear()
        self.calls.clear()

    def report(self, n: int) -> str:
        rows = sorted(self.total.items(), key=lambda kv: -kv[1])
        return "\n".join(f"          {k:20} {v * 1000 / n:6.2f} ms/img"
                         f"  ({self.calls[k] / n:.2f} calls)" for k, v in rows)


def run_level(level: str, n: int, seed: int, verbose: bool = False) -> dict:
    rng = np.random.default_rng(seed)
    errs, conf_wrong, times, cpu, reasons = [], 0, [], [], {}
    for i in range(n):
        spec, v, img = make_case(level, rng)
        prof = load_profile(spec.profile())
        t0, c0 = time.perf_counter(), time.process_time()
        r = read_gauge(img, prof, **meter_rows.READ_KW)
        times.append((time.perf_counter() - t0) * 1000)
        cpu.append((time.process_time() - c0) * 1000)
        if r.value is None:
            first = meter_rows.deciding_reason(r.error)
            key = first.split(" (")[0] if "confidence" not in first else first
            reasons[key] = reasons.get(key, 0) + 1
            continue
        e = abs(r.value - v) / prof.full_scale * 100
        errs.append(e)
        if e > 2.0:
            conf_wrong += 1
            if verbose:
                print(f"  wrong: {level} #{i} {spec.name} true={v:.4f} got={r.value:.4f} "
                      f"conf={r.confidence:.2f}")
    e = np.array(errs) if errs else np.array([np.nan])
    return {
        "readable": 100.0 * len(errs) / n,
        "mae": float(np.mean(e)),
        "p95": float(np.percentile(e, 95)),
        "conf_wrong": 100.0 * conf_wrong / max(len(errs), 1),
        "ms": float(np.mean(times)),
        "ms_p95": float(np.percentile(times, 95)),
        "cpu_ms": float(np.mean(cpu)),
        "reasons": reasons,
    }


PAPER_TABLE2 = [  # image, intersection (x_p, y_p), l, L, val, v, epsilon (MPa)
    ("a", (61.55, 195.65), 9.0, 12.2, 0.294, 0.300, 0.006),
    ("b", (79.54, 78.03), 5.6, 10.5, 1.353, 1.370, 0.017),
    ("c", (210.71, 69.54), 7.6, 12.2, 2.563, 2.560, 0.003),
    ("d", (237.39, 197.62), 7.0, 12.2, 3.758, 3.750, 0.008),
]


def table2(seed: int) -> None:
    xy = [(x, y) for _, x, y in PAPER_TABLE1]
    vals = [v for v, _, _ in PAPER_TABLE1]
    print("\nTable 2 of seed 000 (0-4 MPa gauge, Table 1 ticks)")
    print("  eq. 21 on the paper's own intersection points:")
    print("   img    l(paper)  L(paper)   val(paper)   l      L      val(eq.21)")
    for name, p, pl, pL, pval, _, _ in PAPER_TABLE2:
        v, l_, big_l, _ = eq21_reading(p, xy, vals)
        print(f"   {name}     {pl:5.1f}    {pL:5.1f}     {pval:7.3f}     {l_:5.2f}  {big_l:5.2f}"
              f"  {v:7.4f}")
    spec = STOCK_SPECS[0]
    prof = load_profile(resource("gauges", "paper_0_4mpa.json"))
    rng = np.random.default_rng(seed)
    print("  this reader on rendered Table-1 gauges at the true readings:")
    print("   img   v (MPa)  eps paper  | crop: val    eps   | oblique frame: val    eps")
    e_paper, e_crop, e_view = [], [], []
    for name, _, _, _, _, v, eps in PAPER_TABLE2:
        rc = read_gauge(render_dial(spec, v, 300), prof)
        img, _ = render_view(spec, v, fill=0.6, tilt_deg=25, tilt_axis_deg=30, roll_deg=8,
                             glare=0.3, noise_sigma=3, jpeg_quality=85, rng=rng)
        rv = read_gauge(img, prof)

        def f(r, v=v):
            return ("   none      -   " if r.value is None
                    else f"{r.value:7.4f}  {abs(r.value - v):6.4f}")
        print(f"   {name}    {v:6.3f}   {eps:6.3f}    | {f(rc)}   | {f(rv)}")
        e_paper.append(eps)
        if rc.value is not None:
            e_crop.append(abs(rc.value - v))
        if rv.value is not None:
            e_view.append(abs(rv.value - v))

    def m(e):
        return (f"{np.mean(e):.4f} MPa = {np.mean(e) / 4 * 100:.2f} % FS" if e else "n/a")
    print(f"   mean error: paper {m(e_paper)}; crops {m(e_crop)}; oblique {m(e_view)}")


ALL_ROWS = ("stock", "table2", "tuning", "heldout", "cal-same", "cal-ref")


def warm_up() -> None:
    """One-time costs out of the timed readings (as ``bench/meter_ab.py`` does): every
    module of the reader imported (a reading imports some on first use, compiled from
    source where no bytecode is written), the keypoint model loaded, one reading made."""
    for mod in pkgutil.iter_modules(meter_pkg.__path__):
        if mod.name != "__main__":
            importlib.import_module(f"{meter_pkg.__name__}.{mod.name}")
    importlib.import_module(f"{meter_pkg.__name__}.keypoints").load_model()
    read_gauge(render_dial(STOCK_SPECS[1], 0.5), STOCK_SPECS[1].profile())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=200, help="images per level")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--levels", default="clean,field,hard")
    ap.add_argument("-v", "--verbose", action="store_true", help="list confident wrong readings")
    ap.add_argument("--cv-threads", type=int, default=1,
                    help="OpenCV threads (1: per-core figures; 0: OpenCV's default)")
    ap.add_argument("--steps", action="store_true",
                    help="also print the CPU time per reader step (slightly slower overall)")
    ap.add_argument("--rows", default=",".join(ALL_ROWS),
                    help=f"comma-separated rows to run, of {', '.join(ALL_ROWS)}")
    ap.add_argument("--family", default="",
                    help="tuning families for the styled rows (comma-separated; default all "
                         f"of {', '.join(TUNING_FAMILIES)})")
    ap.add_argument("--split", default="both", choices=("both", "tuning", "heldout"),
                    help="the split the calibrated rows (cal-same, cal-ref) run on; the "
                         f"held-out family is {HELD_OUT_FAMILY}")
    ap.add_argument("--heldout", default=HELD_OUT_FAMILY, choices=HELD_OUT_CHOICES,
                    help=f"the family of the held-out rows (default {HELD_OUT_FAMILY}; the "
                         "others are former held-out families, looked at since, kept to "
                         "re-run earlier figures)")
    ap.add_argument("--dump", default="",
                    help="write refused or wrong tuning-family images with their truth to this "
                         "folder (never the held-out family's)")
    ap.add_argument("--learned-fallback", action=argparse.BooleanOptionalAction, default=True,
                    help="let read_gauge try the learned keypoints where the classical reader "
                         "refuses (on by default, as in the reader)")
    ap.add_argument("--learned-confirm", action="store_true",
                    help="let read_gauge's angles path ask the learned keypoints to confirm "
                         "what its classical estimates leave open (off by default)")
    args = ap.parse_args(argv)
    meter_rows.READ_KW["learned_fallback"] = args.learned_fallback
    meter_rows.READ_KW["learned_confirm"] = args.learned_confirm
    args.rows = args.rows.split(",")
    bad = [r for r in args.rows if r not in ALL_ROWS]
    bad += [f"level {lv}" for lv in args.levels.split(",") if lv not in GOALS]
    bad += [f"family {f}" for f in args.family.split(",") if f and f not in TUNING_FAMILIES]
    if bad:
        ap.error(f"unknown {', '.join(bad)} (rows: {', '.join(ALL_ROWS)}; levels: "
                 f"{', '.join(GOALS)}; tuning families: {', '.join(TUNING_FAMILIES)})")
    if args.cv_threads > 0:
        cv2.setNumThreads(args.cv_threads)
    timer = StepTimer() if args.steps else None
    warm_up()
    print(f"meter bench: n={args.n} per level, seed={args.seed}, OpenCV threads="
          f"{cv2.getNumThreads()}, load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cpus,"
          f" timed after the reader's modules and keypoint model are loaded and one warm-up "
          f"reading")
    if "stock" in args.rows:
        print(f"{'level':6} {'readable%':>9} {'MAE%FS':>7} {'p95%FS':>7} {'confwrong%':>10} "
              f"{'ms/img':>7} {'ms p95':>7} {'cpu ms':>7}   goals (readable, MAE, confwrong, "
              "ms)")
    for level in args.levels.split(",") if "stock" in args.rows else []:
        if timer:
            timer.reset()
        t0 = time.perf_counter()
        r = run_level(level, args.n, args.seed * 1000 + list(GOALS).index(level), args.verbose)
        g = GOALS[level]
        print(f"{level:6} {r['readable']:9.1f} {r['mae']:7.3f} {r['p95']:7.3f} "
              f"{r['conf_wrong']:10.2f} {r['ms']:7.2f} {r['ms_p95']:7.2f} {r['cpu_ms']:7.2f}   "
              f">={g[0]:.0f}%, <={g[1]:.2f}, <={g[2]:.1f}%, <={g[3]:.0f} ms"
              f"   [{time.perf_counter() - t0:.0f} s]")
        if r["reasons"]:
            top = sorted(r["reasons"].items(), key=lambda kv: -kv[1])[:4]
            print("        no-reading reasons: " + "; ".join(f"{k} x{c}" for k, c in top))
        if timer:
            print("        CPU per step (nested steps also inside their parents):")
            print(timer.report(args.n))
    if "table2" in args.rows:
        table2(args.seed)
    if any(r in args.rows for r in ("tuning", "heldout", "cal-same", "cal-ref")):
        print(f"\nissue 11 rows: styled gauges (held-out family: {args.heldout}); wrong = "
              f"returned and > {WRONG_PCT_FS:g} % FS off; CPU ms of read_gauge on one core")
        print(HEADER)
        uncalibrated_rows(args, args.levels.split(","))
        calibrated_rows(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
