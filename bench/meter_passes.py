"""Which passes the uncalibrated reader makes per reading, and what it computes twice.

    python bench/meter_passes.py [--n 30] [--seeds 1,2] [--levels clean,field,hard]
    python bench/meter_passes.py --repeats [...]

Renders the images ``bench/meter_ab.py`` reads (the tuning families, or ``--families``),
warms the reader up, then reads them all.  By default each pass of :data:`PASSES` is
wrapped in ``time.process_time`` (every call, nested ones too) and the script prints, by
level: the CPU share of the readings by what read them (the scale path, the profile's
angles, the learned keypoints, or refused), how often the profile's angles and the learned
keypoints ran and refused, and the calls and inclusive CPU per reading of each pass.

``--repeats``: the steps of :data:`REPEATS` are timed on their own (the outermost call of
each) and keyed by their arguments' contents (arrays hashed, outside the timing); a call
whose key was seen before in the same reading repeats work done already, and its CPU is
what that repeat costs.  The held-out family is never read here.
"""

from __future__ import annotations

import argparse
import hashlib
import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.meter_profile import reader_and_cases  # noqa: E402
from sim_robot.gauge_styles import TUNING_FAMILIES  # noqa: E402

# (module of app.core.meter, function): the passes counted
PASSES = (
    ("pointer", "read_normalised"), ("angles", "read_by_angles"),
    ("ring_centre", "ring_centre"), ("needle", "find_needle"), ("arc_fit", "fit_profile_arc"),
    ("learned", "keypoint_reading"), ("keypoints", "predict_keypoints"),
    ("oblique", "find_rectifier"), ("dial", "find_dial_candidates"), ("rim", "find_crop_rim"),
    ("ring_centre", "hub_is_perspective_centre"), ("pivot_checks", "second_look_allowed"),
    ("hidden_root", "pointer_about_ring"), ("dial", "rectify_projective"),
    ("search", "read_vote_rims"), ("denoise", "quieten"), ("scale", "find_scale"),
)
# steps whose repeats with equal inputs are looked for
REPEATS = (
    ("arc_fit", "bands"), ("tick_band", "short_runs"), ("tick_band", "tick_ring_rows"),
    ("tick_band", "ring_evidence"), ("counts", "col_counts"), ("scale", "polar"),
    ("pointer", "read_normalised"), ("pointer", "dark_features"),
    ("angles", "median_face_grey"), ("ring_centre", "_trimmed_circle"),
)


def _key(x):
    """The contents of an argument, arrays hashed (a callable by its identity)."""
    if isinstance(x, np.ndarray):
        return x.shape, str(x.dtype), hashlib.sha1(np.ascontiguousarray(x).tobytes()).digest()
    if isinstance(x, (list, tuple)):
        return tuple(_key(v) for v in x)
    if isinstance(x, dict):
        return tuple(sorted((str(k), _key(v)) for k, v in x.items()))
    if callable(x):
        return id(x)
    return repr(x)


def _wrap(mods: dict, steps, make) -> None:
    """Replace each step, in every module that holds it, by ``make(name, function)``."""
    for mod_name, fn in steps:
        f = getattr(mods[mod_name], fn)
        w = make(f"{mod_name}.{fn}", f)
        for m in mods.values():
            if getattr(m, fn, None) is f:
                setattr(m, fn, w)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=30, help="images per level and seed")
    ap.add_argument("--seeds", default="1,2")
    ap.add_argument("--levels", default="clean,field,hard")
    ap.add_argument("--families", default=",".join(TUNING_FAMILIES))
    ap.add_argument("--repeats", action="store_true", help="the CPU of repeated steps")
    args = ap.parse_args(argv)
    mods, cases = reader_and_cases(ap, args)
    from app.core.meter import load_profile, read_gauge
    read_gauge(cases[0][2], load_profile(cases[0][3]["profile"]))
    calls: dict = defaultdict(lambda: [0, 0.0])  # name -> [calls, cpu s]
    outcome: dict = defaultdict(lambda: [0, 0.0])  # what the pass said -> [calls, cpu s]
    seen: set = set()
    depth = [0]

    def counted(name, f):
        def w(*a, **k):
            c0 = time.process_time()
            out = f(*a, **k)
            dt = time.process_time() - c0
            calls[name][0] += 1
            calls[name][1] += dt
            if name == "angles.read_by_angles":
                said = outcome["the profile's angles refused" if "error" in out
                               else "the profile's angles placed the needle"]
            elif name == "learned.keypoint_reading":
                said = outcome["the keypoints refused" if out.value is None
                               else "the keypoints read"]
            else:
                return out
            said[0] += 1
            said[1] += dt
            return out
        return w

    def repeated(name, f):
        def w(*a, **k):
            outer = depth[0] == 0  # (a repeat inside a repeat is counted once)
            key = (name, _key(a), _key(k)) if outer else None
            depth[0] += 1
            c0 = time.process_time()
            try:
                return f(*a, **k)
            finally:
                dt = time.process_time() - c0
                depth[0] -= 1
                if outer:
                    calls[name][0] += 1
                    if key in seen:
                        calls[name][1] += dt
                    seen.add(key)
        return w

    _wrap(mods, REPEATS if args.repeats else PASSES, repeated if args.repeats else counted)
    by_level: dict = {}
    for level, _, img, truth in cases:
        prof = load_profile(truth["profile"])
        seen.clear()
        c0 = time.process_time()
        r = read_gauge(img, prof)
        ms = (time.process_time() - c0) * 1000.0
        got = by_level.setdefault(level, {"n": 0, "ms": 0.0, "by": defaultdict(lambda: [0, 0.0]),
                                          "calls": {}, "outcome": {}})
        got["n"] += 1
        got["ms"] += ms
        by = got["by"]["refused" if r.value is None else r.method]
        by[0] += 1
        by[1] += ms
        for src, dst in ((calls, got["calls"]), (outcome, got["outcome"])):
            for name, (c, t) in src.items():
                acc = dst.setdefault(name, [0, 0.0])
                acc[0] += c
                acc[1] += t
            src.clear()
    for level, got in by_level.items():
        n, tot = got["n"], got["ms"]
        print(f"{level}: {n} readings, cpu ms per reading {tot / n:.1f}")
        if args.repeats:
            rep = sum(t for _, t in got["calls"].values()) * 1000.0
            print(f"    repeated steps: {rep / n:.3f} ms a reading ({100.0 * rep / tot:.1f} %; "
                  f"the hashing of their arguments is in the reading's ms, not in theirs)")
            for name, (c, t) in sorted(got["calls"].items(), key=lambda kv: -kv[1][1]):
                print(f"    {1000.0 * t / n:7.3f} ms  {c / n:6.1f} calls  {name}")
            continue
        for meth, (c, t) in sorted(got["by"].items(), key=lambda kv: -kv[1][1]):
            print(f"    read by {meth:15} {c:3d} readings, {100.0 * t / tot:5.1f} % of the CPU, "
                  f"{t / c:6.1f} ms each")
        for what, (c, t) in sorted(got["outcome"].items()):
            print(f"    {what:40} {c / n:5.2f} a reading, {100.0 * t / (tot / 1000.0):5.1f} % "
                  "of the CPU")
        for name, (c, t) in sorted(got["calls"].items(), key=lambda kv: -kv[1][1]):
            print(f"    {c / n:5.2f} calls  {1000.0 * t / n:6.2f} ms  {name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
