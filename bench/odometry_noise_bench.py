"""The mapper's odometry noise model against the odometry's real errors (issue 13).

    python bench/odometry_noise_bench.py                       # freiburg, edmonton
    python bench/odometry_noise_bench.py --variants edmonton-every2 --seeds 3
    python bench/odometry_noise_bench.py --learnt    # the learnt model (odometry_noise.py)

Runs the laser mapper (MappingConfig(final_pass=True), as the log bench's
"full") on the CARMEN logs with raw-like odometry drawn as in
bench/localisation_bench.py, and at every step records

* the odometry step as the mapper uses it (after its learnt calibration)
  and the covariance its noise model gives that step;
* the scan match, when one was fitted, and its covariance (as fused);

and compares both with the reference's relative motion between the two
scans (only this bench reads the reference). A noise model that is right
has normalised errors e/σ of RMS about 1 and about 5 % of steps beyond 2σ;
RMS well below 1 means the model claims too little confidence (a wrong
match then pulls the estimate), above 1 too much. Printed per log, binned
by the step's turn; the steps where the fused heading is worse than
odometry's by more than 1° are listed with both errors and both σ.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from app.core.localisation import mapping as mapping_mod  # noqa: E402
from app.core.localisation.carmen import read_log  # noqa: E402
from app.core.localisation.evaluate import ate_m, drifting_odometry, rpe  # noqa: E402
from app.core.localisation.mapping import LaserMapper, MappingConfig  # noqa: E402
from app.core.localisation.odometry_noise import OdometryNoiseConfig  # noqa: E402
from app.core.localisation.se2 import relative, wrap  # noqa: E402
from app.core.localisation.slam import scan_points  # noqa: E402
from bench.localisation_bench import CARMEN, VARIANTS, odometry_errors  # noqa: E402

HELD_OUT = ("edmonton-harsh", "edmonton-reversed")


class TracingMapper(LaserMapper):
    """A LaserMapper that keeps, per step, what its fusion saw."""

    def __init__(self, cfg: MappingConfig) -> None:
        super().__init__(cfg)
        self.trace: list[dict] = []

    def odom_covariance(self, u: np.ndarray) -> np.ndarray:
        q = super().odom_covariance(u)
        self.trace.append({"u": np.array(u), "uc": self.calibration.correct(u), "q": q,
                           "prev": np.array(self.poses[-1])})
        return q

    def _submap_refined(self, points, r):
        r, scale, spread, d = super()._submap_refined(points, r)
        dis = 0.0 if d is None else self.cfg.match_disagreement_k ** 2 * np.outer(d, d)
        self.trace[-1]["match"] = (np.array(r.pose),
                                   np.array(r.covariance) * scale + spread + dis,
                                   r.inlier_fraction)
        return r, scale, spread, d


def run(odo: np.ndarray, pts: list[np.ndarray], ref: np.ndarray, cfg: MappingConfig):
    m = TracingMapper(cfg)
    real_match = mapping_mod.match

    def spy(*a, **k):
        r = real_match(*a, **k)
        if len(m.trace) == len(m.poses):  # the step being added: its first match
            m.trace[-1]["match"] = (np.array(r.pose), np.array(r.covariance) * cfg.cov_scale(),
                                    r.inlier_fraction)
        return r

    mapping_mod.match = spy
    try:
        rows = []
        for k, (o, p) in enumerate(zip(odo, pts, strict=True)):
            m.add_scan(o, p)
            if k == 0:
                continue
            t = m.trace[-1]
            truth = relative(ref[k - 1], ref[k])
            e_odo = float(wrap(t["uc"][2] - truth[2]))
            s_odo = math.sqrt(t["q"][2, 2])
            fused = relative(t["prev"], m.poses[k])
            row = {"k": k, "turn": abs(float(truth[2])), "d": math.hypot(*truth[:2]),
                   "e_odo": e_odo, "s_odo": s_odo,
                   "e_fused": float(wrap(fused[2] - truth[2]))}
            if "match" in t:
                pose, cov, inl = t["match"]
                z = relative(t["prev"], pose)
                row["e_match"] = float(wrap(z[2] - truth[2]))
                row["s_match"] = math.sqrt(cov[2, 2])  # as fused (times its scale)
                row["inl"] = inl
            rows.append(row)
    finally:
        mapping_mod.match = real_match
    est = m.finish()
    return rows, (ate_m(est, ref), 100 * rpe(est, ref, 1.0).trans_m, rpe(est, ref, 1.0).rot_deg,
                  m.match_rejected, getattr(getattr(m, "noise", None), "level", math.nan),
                  getattr(m, "match_downweighted", 0))


def report(name: str, rows: list[dict]) -> None:
    d = np.degrees
    bins = [(0, 5), (5, 20), (20, 45), (45, 180)]
    print(f"\n{name}: {len(rows)} steps")
    print(f"{'turn deg':>9} | {'n':>4} | {'odo err rms':>11} {'model σ rms':>11} "
          f"{'e/σ rms':>7} {'>2σ %':>6} | {'match err rms':>13} {'σ rms':>6} {'e/σ rms':>7} "
          f"{'>2σ %':>6} | {'fused rms':>9}")
    for lo, hi in bins + [(0, 180)]:
        sel = [r for r in rows if lo <= d(r["turn"]) < hi]
        if not sel:
            continue
        eo = np.array([r["e_odo"] for r in sel])
        so = np.array([r["s_odo"] for r in sel])
        ms = [r for r in sel if "e_match" in r and r["inl"] >= 0.45]
        em = np.array([r["e_match"] for r in ms]) if ms else np.zeros(1)
        sm = np.array([r["s_match"] for r in ms]) if ms else np.ones(1)
        ef = np.array([r["e_fused"] for r in sel])
        rms = lambda a: float(np.sqrt(np.mean(a * a)))  # noqa: E731
        print(f"{lo:>3}-{hi:<5} | {len(sel):4d} | {d(rms(eo)):11.2f} {d(rms(so)):11.2f} "
              f"{rms(eo / so):7.2f} {100 * np.mean(np.abs(eo) > 2 * so):6.1f} | "
              f"{d(rms(em)):13.2f} {d(rms(sm)):6.2f} {rms(em / sm):7.2f} "
              f"{100 * np.mean(np.abs(em) > 2 * sm):6.1f} | {d(rms(ef)):9.2f}")
    worse = [r for r in rows if abs(r["e_fused"]) > abs(r["e_odo"]) + math.radians(1)]
    print(f"steps where the fused heading is > 1 deg worse than odometry's: {len(worse)}")
    for r in worse[:12]:
        print(f"  scan {r['k']:3d} turn {d(r['turn']):5.1f} deg, {r['d']:.2f} m: odometry "
              f"{d(r['e_odo']):+5.2f} (σ {d(r['s_odo']):4.2f}), match "
              f"{d(r.get('e_match', math.nan)):+5.2f} (σ {d(r.get('s_match', math.nan)):4.2f}),"
              f" fused {d(r['e_fused']):+5.2f} deg")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--logs", default="freiburg,edmonton")
    ap.add_argument("--variants", default="")
    ap.add_argument("--learnt", action="store_true",
                    help="the learnt noise model (OdometryNoiseConfig.learnt); default: the fixed")
    ap.add_argument("--heading-k", type=float, default=None,
                    help="MappingConfig.match_heading_k (default: the config's)")
    args = ap.parse_args()
    rows = [(f, 1, 1.0, False) for f in ("freiburg-101-corrected.log.gz",
                                         "edmonton-corrected.log.gz")
            if any(k and k in f for k in args.logs.split(","))]
    for v in (v for v in args.variants.split(",") if v):
        if v in HELD_OUT:
            print(f"{v} is held out: not looked at here", file=sys.stderr)
            return 2
        fname, every, factor, *rev = VARIANTS[v]
        rows.append((fname, every, factor, bool(rev and rev[0])))
    for fname, every, factor, back in rows:
        log = read_log(CARMEN / fname)
        step = -every if back else every
        pts = scan_points(log)[::step]
        ref = np.array([s.pose for s in log.scans])[::step]
        ref = np.array([relative(ref[0], p) for p in ref])
        all_rows, scores = [], []
        for seed in range(args.seeds):
            odo = drifting_odometry(ref, seed, odometry_errors(factor))
            cfg = MappingConfig(final_pass=True,
                                odometry_noise=OdometryNoiseConfig(learnt=args.learnt))
            if args.heading_k is not None:
                cfg = replace(cfg, match_heading_k=args.heading_k)
            rows_, score = run(odo, pts, ref, cfg)
            all_rows += rows_
            scores.append(score)
        report(f"{fname} every {every} x{factor:g} seeds 0..{args.seeds - 1}", all_rows)
        print("ATE m per seed: " + " ".join(f"{s[0]:.3f}" for s in scores)
              + f"; mean RPE 1 m {np.mean([s[1] for s in scores]):.1f} cm "
              f"{np.mean([s[2] for s in scores]):.2f} deg; matches refused by the gate: "
              + " ".join(str(s[3]) for s in scores) + "; down-weighted: "
              + " ".join(str(s[5]) for s in scores) + "; learnt noise level: "
              + " ".join(f"{s[4]:.2f}" for s in scores))
    return 0


if __name__ == "__main__":
    sys.exit(main())
