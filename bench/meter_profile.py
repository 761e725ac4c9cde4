"""Where the uncalibrated reader's CPU goes, on the tuning rows' images.

    python bench/meter_profile.py [--n 30] [--seeds 1,2] [--levels clean,field] [--top 40]
    python bench/meter_profile.py --wrap [...]    # inclusive CPU of named steps
    python bench/meter_profile.py --calls [...]   # calls per reading, by kind
    python bench/meter_profile.py --no-profile [...]

Renders the images ``bench/meter_ab.py`` reads (the tuning families, or ``--families``),
warms the reader up (every module imported, the keypoint model loaded, one reading), then
reads them all and prints the mean CPU ms per reading by level (``time.process_time``)
and, by default, the top functions by own and by cumulative time under ``cProfile``.

``--wrap``: no profiler; each step of :data:`STEPS` is wrapped in ``time.process_time``
(outermost call only, so a recursive or nested call is not counted twice) and its share of
the CPU printed, by level.  ``--calls``: the Python function calls (the reader's own,
numpy's Python wrappers, others) and the calls into C (numpy's and OpenCV's functions and
methods; arithmetic operators and indexing are not calls and are not counted) made per
reading, counted with ``sys.setprofile``.  The held-out family is never read here.
"""

from __future__ import annotations

import argparse
import cProfile
import importlib
import io
import pkgutil
import pstats
import sys
import time
from pathlib import Path

import cv2

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.meter_ab import FAMILIES, render  # noqa: E402
from sim_robot.gauge_styles import TUNING_FAMILIES  # noqa: E402

# (module of app.core.meter, function) timed by --wrap
STEPS = (
    ("angles", "read_by_angles"), ("pointer", "read_normalised"), ("needle", "find_needle"),
    ("arc_fit", "fit_profile_arc"), ("ring_centre", "ring_centre"),
    ("keypoints", "predict_keypoints"), ("oblique", "find_rectifier"),
    ("tick_comb", "comb_turn"), ("arc_fit", "_ends_fit"), ("ring_centre", "_trimmed_circle"),
    ("scale", "polar"), ("scale", "find_scale"), ("thinning", "zhang_suen"),
    ("rim", "find_crop_rim"), ("dial", "find_dial_candidates"), ("needle", "polar_frame"),
    ("needle_line", "_fit_needle"), ("needle_line", "_centroids"),
    ("hub_edges", "find_hub_edges"), ("pointer", "dark_features"),
    ("denoise", "noise_sigma"), ("needle_axis", "fit_shaft"),
)


def _wrap_steps(mods: dict, acc: dict) -> None:
    """Replace each step of :data:`STEPS`, in every module that holds it, by a wrapper adding
    its CPU (outermost calls only) to ``acc``."""
    depth: dict[str, int] = {}

    def make(name, f):
        def timed(*a, **k):
            d = depth.get(name, 0)
            depth[name] = d + 1
            c0 = time.process_time()
            try:
                return f(*a, **k)
            finally:
                depth[name] = d
                if d == 0:
                    acc[name] = acc.get(name, 0.0) + time.process_time() - c0
        return timed

    for mod_name, fn in STEPS:
        f = getattr(mods[mod_name], fn)
        w = make(f"{mod_name}.{fn}", f)
        for m in mods.values():
            if getattr(m, fn, None) is f:
                setattr(m, fn, w)


def _counter(counts: dict):
    def prof(frame, event, arg):
        if event == "call":
            fn = frame.f_code.co_filename
            kind = "py: the reader" if "/app/core/meter/" in fn else \
                "py: numpy's wrappers" if "/numpy/" in fn else "py: other"
            counts[kind] = counts.get(kind, 0) + 1
        elif event == "c_call":
            counts["C: numpy, OpenCV, builtins"] = counts.get("C: numpy, OpenCV, builtins",
                                                               0) + 1
    return prof


def reader_and_cases(ap: argparse.ArgumentParser, args) -> tuple[dict, list]:
    """The reader's modules by name (one core, the keypoint network loaded) and the
    rendered cases of ``args`` (``--n``, ``--seeds``, ``--levels``, ``--families``)."""
    families = tuple(args.families.split(","))
    if any(f not in FAMILIES for f in families):
        ap.error("families are " + ", ".join(FAMILIES))
    cv2.setNumThreads(1)
    import app.core.meter
    from app.core.meter.keypoints import load_model
    mods = {m.name: importlib.import_module("app.core.meter." + m.name)
            for m in pkgutil.iter_modules(app.core.meter.__path__) if m.name != "__main__"}
    load_model()
    cases = []
    for s in args.seeds.split(","):
        cases += render(args.n, int(s), args.levels.split(","), families)
    return mods, cases


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=30, help="images per level and seed")
    ap.add_argument("--seeds", default="1,2")
    ap.add_argument("--levels", default="clean,field")
    ap.add_argument("--families", default=",".join(TUNING_FAMILIES))
    ap.add_argument("--top", type=int, default=40)
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--no-profile", action="store_true", help="only the CPU per reading")
    mode.add_argument("--wrap", action="store_true", help="inclusive CPU of named steps")
    mode.add_argument("--calls", action="store_true", help="calls per reading, by kind")
    args = ap.parse_args(argv)
    mods, cases = reader_and_cases(ap, args)
    from app.core.meter import load_profile, read_gauge
    items = [(lv, img, load_profile(truth["profile"])) for lv, _, img, truth in cases]
    read_gauge(items[0][1], items[0][2])
    acc: dict[str, dict[str, float]] = {}
    if args.wrap:
        cur: dict[str, float] = {}
        _wrap_steps(mods, cur)
    ms: dict[str, list[float]] = {}
    counts: dict[str, dict[str, int]] = {}
    prof = cProfile.Profile()
    for lv, img, p in items:
        if args.wrap:
            cur.clear()
        c0 = time.process_time()
        if args.no_profile or args.wrap:
            read_gauge(img, p)
        elif args.calls:
            sys.setprofile(_counter(counts.setdefault(lv, {})))
            try:
                read_gauge(img, p)
            finally:
                sys.setprofile(None)
        else:
            prof.runcall(read_gauge, img, p)
        ms.setdefault(lv, []).append((time.process_time() - c0) * 1000.0)
        if args.wrap:
            for k, v in cur.items():
                acc.setdefault(lv, {})[k] = acc.get(lv, {}).get(k, 0.0) + v
    how = "" if args.no_profile or args.wrap else " (under the profiler)"
    for lv, v in ms.items():
        print(f"{lv:6} {len(v)} readings, cpu ms per reading {sum(v) / len(v):.1f}{how}")
        if args.wrap:
            tot = sum(v) / 1000.0
            for k, t in sorted(acc.get(lv, {}).items(), key=lambda x: -x[1]):
                print(f"    {100.0 * t / tot:5.1f} %  {1000.0 * t / len(v):6.2f} ms  {k}")
        if args.calls:
            for k, c in sorted(counts.get(lv, {}).items()):
                print(f"    {c / len(v):8.0f} per reading  {k}")
    if args.no_profile or args.wrap or args.calls:
        return 0
    for key in ("tottime", "cumulative"):
        s = io.StringIO()
        pstats.Stats(prof, stream=s).sort_stats(key).print_stats(args.top)
        print(s.getvalue())
    return 0


if __name__ == "__main__":
    sys.exit(main())
