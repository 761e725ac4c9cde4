"""Where the laser mapper's local steps fail under larger odometry errors (issue 13).

    python bench/step_diagnosis.py --variant edmonton-every2-reversed-x1.5 --seeds 0,1,2
    python bench/step_diagnosis.py --log edmonton --seeds 0 --method full

Runs a method of bench/localisation_bench.py (default "full") on a tuning log
or a development variant (held-out variants are refused, as in
bench/loop_edge_errors.py) and scores, against the reference (diagnosis
only; the mapper never sees it):

- the odometry's drawn systematic errors (scale, turn gain, turn per metre),
  the ones it realises (the drawn ones plus what the per-step noise holds in
  common: evaluate.realised_odometry_errors, what exact matches would teach)
  and what the mapper's calibration learnt (its corrections invert them);
- the fused steps' heading error as an offset per step plus a gain of the
  turn, with their standard errors (a bias, or a random walk's sum);
- each local step: the prediction's error (calibrated odometry from the
  previous estimate, against the reference step), whether the match was
  fused (a full or a partial fit, partial_overlap.py), failed (inlier share
  under the minimum and no partial fit: dead reckoned) or refused by the
  innovation test, and the fused step's error; the prediction's error
  against the search window the step had (``icp_window_*``);
- the online closures' errors, the online map's ATE (before ``finish``) and
  the final ATE.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import app.core.localisation.mapping as mapping_mod  # noqa: E402
from app.core.localisation.evaluate import (  # noqa: E402
    ate_m,
    drifting_odometry,
    realised_odometry_errors,
)
from app.core.localisation.mapping import LaserMapper  # noqa: E402
from app.core.localisation.se2 import relative, wrap  # noqa: E402
from bench.localisation_bench import method_config, odometry_errors  # noqa: E402
from bench.loop_edge_errors import load  # noqa: E402


def drawn_errors(seed: int, factor: float) -> tuple[float, float, float]:
    """The systematic errors drifting_odometry draws for ``seed`` (same stream)."""
    e = odometry_errors(factor)
    rng = np.random.default_rng(seed)
    return (1 + rng.normal(0, e.scale_sigma), 1 + rng.normal(0, e.yaw_gain_sigma),
            rng.normal(0, e.yaw_drift_sigma_rad_per_m))


def step_error(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    d = relative(b, a)
    return math.hypot(d[0], d[1]), math.degrees(float(wrap(d[2])))


def heading_bias(err_deg, turn_deg):
    """Least squares err = offset + gain · turn (degrees) with the standard
    errors of (offset, gain): a heading bias of the matches is an offset or a
    gain beyond a few standard errors; a sum over the log is not (the steps'
    errors add as a random walk, √n · rms)."""
    e, t = np.asarray(err_deg, float), np.asarray(turn_deg, float)
    x = np.c_[np.ones_like(t), t]
    c = np.linalg.lstsq(x, e, rcond=None)[0]
    s2 = float(np.sum((e - x @ c) ** 2)) / max(len(e) - 2, 1)
    return float(c[0]), float(c[1]), np.sqrt(np.diag(s2 * np.linalg.inv(x.T @ x)))


def diagnose(pts, ref, odo, cfg, verbose: bool):
    calls = []
    orig = mapping_mod.match

    def match(points, reference, guess, *a, **k):
        r = orig(points, reference, guess, *a, **k)
        calls.append((np.array(guess, float), a[1] if len(a) > 1 else k.get("window_xy_m"),
                      a[2] if len(a) > 2 else k.get("window_theta_rad"), r.inlier_fraction,
                      np.array(r.pose, float)))
        return r

    mapping_mod.match = match
    m = LaserMapper(cfg)
    rows = []
    try:
        for k, (o, p) in enumerate(zip(odo, pts, strict=True)):
            f0, r0, p0 = m.icp_failures, m.match_rejected, m.partial_matches
            n0 = len(calls)
            prev = m.poses[-1].copy() if m.poses else None
            m.add_scan(o, p)
            if k == 0:
                continue
            truth = relative(ref[k - 1], ref[k])
            guess, wxy, wth, inl, fit = calls[n0] if len(calls) > n0 else (None,) * 5
            pe = step_error(relative(prev, guess), truth) if guess is not None else (0, 0)
            fe = step_error(relative(prev, fit), truth) if fit is not None else (0, 0)
            z = next(e.z for e in reversed(m.edges) if e.i == k - 1 and e.j == k and not e.loop)
            ze = step_error(z, truth)
            state = "failed" if m.icp_failures > f0 else \
                "refused" if m.match_rejected > r0 else \
                "partial" if m.partial_matches > p0 else "fused"
            rows.append((k, state, pe, math.degrees(wth or 0), wxy or 0, inl, fe, ze,
                         math.degrees(abs(truth[2])), math.degrees(float(truth[2]))))
        online = np.array(m.poses)
        est = m.finish()
    finally:
        mapping_mod.match = orig
    return m, online, est, rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--log", default="edmonton", choices=("edmonton", "freiburg"))
    ap.add_argument("--variant", default="")
    ap.add_argument("--seeds", default="0")
    ap.add_argument("--method", default="full")
    ap.add_argument("--set", default="",
                    help="MappingConfig fields to change, e.g. min_inlier_fraction=0.3")
    ap.add_argument("--verbose", action="store_true", help="print every failed step")
    args = ap.parse_args()
    pts, ref, factor = load(args.log, args.variant or None)
    for seed in (int(s) for s in args.seeds.split(",")):
        odo = drifting_odometry(ref, seed, odometry_errors(factor))
        cfg = method_config(args.method)
        if args.set:
            cfg = dataclasses.replace(cfg, **eval(f"dict({args.set})"))
        m, online, est, rows = diagnose(pts, ref, odo, cfg, args.verbose)
        sc, g, b = drawn_errors(seed, factor)
        cal = m.calibration
        print(f"\n{args.variant or args.log} draw {seed}: ATE online {ate_m(online, ref):.3f} m, "
              f"final {ate_m(est, ref):.3f} m; closures {m.loop_closures} "
              f"(dropped {m.loop_rejected}), final-pass {m.final_closures}, "
              f"ties {m.long_range_ties}")
        print(f"  drawn: scale {sc:.4f}, turn gain {g:.4f}, drift {math.degrees(b):+.3f} deg/m;"
              f" ideal correction: scale {1 / sc:.4f}, gain {1 / g:.4f}, "
              f"{math.degrees(-b / g):+.3f} deg/m; learnt: scale {cal.scale:.4f}, "
              f"gain {cal.turn_gain:.4f}, {math.degrees(cal.turn_per_m):+.3f} deg/m")
        rs_, rg, rb = realised_odometry_errors(odo, ref)
        print(f"  realised (drawn + the per-step noise's common part): scale {rs_:.4f}, "
              f"gain {rg:.4f}, drift {math.degrees(rb):+.3f} deg/m; its correction: "
              f"scale {1 / rs_:.4f}, gain {1 / rg:.4f}, {math.degrees(-rb / rg):+.3f} deg/m")
        by = {}
        for r in rows:
            by.setdefault(r[1], []).append(r)
        for state in ("fused", "partial", "failed", "refused"):
            rs = by.get(state, [])
            if not rs:
                continue
            pe = np.array([r[2] for r in rs])
            ze = np.array([r[7] for r in rs])
            fe = np.array([r[6] for r in rs])
            print(f"  {state:>7}: {len(rs):3d} steps; prediction off "
                  f"{100 * np.mean(pe[:, 0]):.1f} cm {np.sqrt(np.mean(pe[:, 1] ** 2)):.2f} deg "
                  f"rms (max {np.abs(pe[:, 1]).max():.1f}); fit off "
                  f"{100 * np.median(fe[:, 0]):.1f} cm med {np.median(np.abs(fe[:, 1])):.2f} "
                  f"deg med; fused step off {100 * np.mean(ze[:, 0]):.1f} cm "
                  f"{np.sqrt(np.mean(ze[:, 1] ** 2)):.2f} deg rms, sum {ze[:, 1].sum():+.1f} deg")
        for r in rows:
            if r[1] != "fused" or args.verbose and abs(r[7][1]) > 1.0:
                print(f"    step {r[0]:3d} {r[1]:>7}: turn {r[8]:5.1f} deg, prediction off "
                      f"{100 * r[2][0]:4.0f} cm {r[2][1]:+5.1f} deg (window {100 * r[4]:.0f} cm "
                      f"{r[3]:.1f} deg), inliers {r[5]:.2f}, fit off {100 * r[6][0]:4.0f} cm "
                      f"{r[6][1]:+5.1f} deg, step off {100 * r[7][0]:3.0f} cm {r[7][1]:+5.1f} deg")
        fused = by.get("fused", [])
        if len(fused) > 2:
            off, gain, se = heading_bias([r[7][1] for r in fused], [r[9] for r in fused])
            print(f"  fused steps' heading error = offset + gain x turn: offset {off:+.3f} "
                  f"+- {se[0]:.3f} deg a step, gain {100 * gain:+.2f} +- {100 * se[1]:.2f} % "
                  f"(standard errors; draws of one variant share their scans)")
        big = [r for r in rows if r[1] == "fused" and abs(r[7][1]) > 1.0]
        print(f"  fused steps > 1 deg off: {len(big)}, sum {sum(r[7][1] for r in big):+.1f} deg")
        errs = []
        for e in m.edges:
            if e.loop:
                d = relative(ref[e.i], ref[e.j])
                errs.append(step_error(e.z, d))
        if errs:
            a = np.array(errs)
            print(f"  loop edges {len(a)}: > 0.3 m or 2 deg off: "
                  f"{int(np.sum((a[:, 0] > 0.3) | (np.abs(a[:, 1]) > 2)))}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
