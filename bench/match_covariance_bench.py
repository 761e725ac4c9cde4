"""The scan-to-submap match's covariance against its real errors (issue 13).

    python bench/match_covariance_bench.py                        # freiburg, edmonton
    python bench/match_covariance_bench.py --seeds 3 --variants edmonton-every2
    python bench/match_covariance_bench.py --mapper-covariance olson   # the old mapper

Runs the laser mapper (MappingConfig(final_pass=True), as the log bench's
"full") on the CARMEN logs with raw-like odometry drawn as in
bench/localisation_bench.py. At every step whose ICP fit is refined on the
local submap (mapping.py, ``_submap_refined``) it keeps the match and its
local landmarks, and scores two covariances of the same match
(match_covariance.py): Olson's times the mapper's ``icp_cov_scale`` (what
the mapper fused until now), the same plus the submap's own uncertainty
(match_covariance.py 3., ``submap_spread``: "+ spread θ" its heading part
with its lever arm, "+ spread full" all of it; in the clean rows, whose
keyframes are at their reference poses, the spread is not added) and the
residual one (Censi's form with correlated beams, fused as it is). Only
this bench reads the reference.

Two errors per match, each in the scan's own frame (x ahead, y left, θ):

* **in situ**: the match's pose relative to the nearest local landmark,
  against the reference's relative pose: what the pose graph is told,
  errors of the map's landmarks included;
* **clean**: the same scan matched again (same guess, same window) on a
  submap of the same landmarks placed at their *reference* poses relative
  to that landmark: the matcher's own error (plus the reference's; the
  logs' reference is itself a SLAM estimate, and ``--reference-check``
  measures how much of the error it carries: the scan matched on its past
  and on its future keyframes, whose errors share only the reference's
  error at the scan).

A covariance that is right has e/σ with RMS about 1 on each axis, about
4.6 % of |e/σ| beyond 2 and 0.3 % beyond 3, and a mean NEES eᵀΣ⁻¹e of 3.
Printed by situation: every match; corridor-like scans (the smallest
eigenvalue of Σ n nᵀ over the scan's line normals below 0.15 of the
largest); few points (under 100 after pre-processing); big turns (the
odometry turned over 15° since the last scan).
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

from app.core.localisation.carmen import read_log  # noqa: E402
from app.core.localisation.evaluate import ate_m, drifting_odometry  # noqa: E402
from app.core.localisation.icp import scan_normals  # noqa: E402
from app.core.localisation.mapping import LaserMapper, MappingConfig  # noqa: E402
from app.core.localisation.se2 import compose, relative, wrap  # noqa: E402
from app.core.localisation.slam import scan_points  # noqa: E402
from app.core.localisation.submap_match import Submap, covariance, match_submap  # noqa: E402
from bench.localisation_bench import CARMEN, VARIANTS, odometry_errors  # noqa: E402

HELD_OUT = ("edmonton-harsh", "edmonton-reversed")
LOGS = {"freiburg": "freiburg-101-corrected.log.gz", "edmonton": "edmonton-corrected.log.gz"}
MODELS = ("olson x scale", "+ spread θ", "+ spread full", "residual")


class TracingMapper(LaserMapper):
    """A LaserMapper that keeps each submap match with what it was matched on."""

    def __init__(self, cfg: MappingConfig) -> None:
        super().__init__(cfg)
        self.trace: list[dict] = []
        self._turn = 0.0

    def odom_covariance(self, u: np.ndarray) -> np.ndarray:
        self._turn = abs(float(u[2]))
        return super().odom_covariance(u)

    def _submap_refined(self, points, r):
        guess = np.array(r.pose)
        r, scale, spread, d = super()._submap_refined(points, r)
        local = self.landmarks[-self.cfg.local_landmarks:]
        self.trace.append({"k": len(self.poses), "points": points, "guess": guess,
                           "pose": np.array(r.pose), "turn": self._turn,
                           "spread": {p: np.asarray(self.submap_spread(r.pose, p))
                                      for p in ("heading", "full")},
                           "local": [(lm.node, np.array(self.poses[lm.node]), lm.points)
                                     for lm in local]})
        return r, scale, spread, d


def _in_frame(pose, cov: np.ndarray) -> np.ndarray:
    c, s = math.cos(pose[2]), math.sin(pose[2])
    rot = np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])
    return rot @ cov @ rot.T


def _corridor(points: np.ndarray) -> bool:
    n, planar = scan_normals(points)
    n = n[planar]
    if len(n) < 3:
        return True
    w = np.linalg.eigvalsh(n.T @ n)
    return bool(w[0] < 0.15 * w[1])


def _covs(points, sub: Submap, pose, scale: float, spread=None) -> dict[str, np.ndarray]:
    """The covariances of ``pose``, in the scan's frame, as the mapper fuses
    them: Olson's scaled, plus the submap's own uncertainty (its heading
    part, or all of it; none given for the clean submap, whose keyframes
    are at their reference poses), and the residual one."""
    olson = covariance(points, sub, pose, 2, "olson") * scale
    spread = spread or {"heading": 0.0, "full": 0.0}
    return {"olson x scale": _in_frame(pose, olson),
            "+ spread θ": _in_frame(pose, olson + spread["heading"]),
            "+ spread full": _in_frame(pose, olson + spread["full"]),
            "residual": _in_frame(pose, covariance(points, sub, pose, 2, "residual"))}


def score(trace: list[dict], ref: np.ndarray, cfg: MappingConfig) -> list[dict]:
    """Per traced match: its in-situ and clean errors and both covariances."""
    rows = []
    scale = cfg.icp_cov_scale
    for t in trace:
        k, pose, pts = t["k"], t["pose"], t["points"]
        anchor = min(t["local"], key=lambda lm: math.hypot(*(lm[1][:2] - pose[:2])))
        a_node, a_est = anchor[0], anchor[1]
        truth = compose(a_est, relative(ref[a_node], ref[k]))  # in the estimate's frame
        sub = Submap([(pose_i, p) for _, pose_i, p in t["local"]], cfg.submap_cfg)
        e_situ = relative(truth, pose)
        clean_sub = Submap([(compose(a_est, relative(ref[a_node], ref[n])), p)
                            for n, _, p in t["local"]], cfg.submap_cfg)
        rc = match_submap(pts, clean_sub, t["guess"], cfg.submap_window_xy_m,
                          cfg.submap_window_theta_rad)
        e_clean = relative(truth, rc.pose)
        rows.append({"k": k, "turn": t["turn"], "n": len(pts), "corridor": _corridor(pts),
                     "situ": (e_situ, _covs(pts, sub, pose, scale, t["spread"])),
                     "clean": (e_clean, _covs(pts, clean_sub, rc.pose, scale))})
    return rows


def reference_check(pts: list[np.ndarray], ref: np.ndarray, cfg: MappingConfig,
                    every: int = 7) -> None:
    """Each scan matched on its five past and its five future keyframes at
    their reference poses: the two errors share the reference's own error at
    the scan, and nothing else."""
    past, future = [], []
    guess = np.array([0.03, -0.03, math.radians(0.5)])
    for k in range(6, len(pts) - 6, every):
        for span, out in ((range(k - 5, k), past), (range(k + 1, k + 6), future)):
            sub = Submap([(relative(ref[k], ref[i]), pts[i]) for i in span], cfg.submap_cfg)
            out.append(match_submap(pts[k], sub, guess, cfg.submap_window_xy_m,
                                    cfg.submap_window_theta_rad).pose)
    a, b = np.array(past), np.array(future)
    print(f"reference check ({len(a)} scans): error on past / future keyframes, rms, and "
          "their correlation (the reference's share of the variance)")
    for i, name in enumerate(("x cm", "y cm", "θ deg")):
        f = 100 if i < 2 else math.degrees(1)
        print(f"  {name:>6}: past {f * np.sqrt(np.mean(a[:, i] ** 2)):5.2f}, future "
              f"{f * np.sqrt(np.mean(b[:, i] ** 2)):5.2f}, correlation "
              f"{np.corrcoef(a[:, i], b[:, i])[0, 1]:+.2f}, rms of the difference / √2 "
              f"{f * np.sqrt(np.mean((a[:, i] - b[:, i]) ** 2) / 2):5.2f}")


SITUATIONS = [("all", lambda r: True), ("corridor-like", lambda r: r["corridor"]),
              ("few points <100", lambda r: r["n"] < 100),
              ("big turn >15deg", lambda r: r["turn"] > math.radians(15)),
              ("none of those", lambda r: not r["corridor"] and r["n"] >= 100
               and r["turn"] <= math.radians(15))]


def report(name: str, rows: list[dict]) -> None:
    print(f"\n{name}: {len(rows)} submap matches")
    print(f"{'situation':>16} {'n':>4} {'error':>6} {'model':>14} | {'err rms cm cm deg':>18} | "
          f"{'σ rms cm cm deg':>18} | {'e/σ rms x y θ':>15} | {'>2σ %':>5} {'>3σ %':>5} | "
          f"{'NEES':>6}")
    for sname, pick in SITUATIONS:
        sel = [r for r in rows if pick(r)]
        if not sel:
            continue
        for which in ("situ", "clean"):
            e = np.array([r[which][0] for r in sel])
            e[:, 2] = wrap(e[:, 2])
            for model in MODELS:
                cov = np.array([r[which][1][model] for r in sel])
                sig = np.sqrt(np.maximum(np.diagonal(cov, axis1=1, axis2=2), 1e-18))
                z = e / sig
                nees = np.array([float(v @ np.linalg.solve(c + np.eye(3) * 1e-15, v))
                                 for v, c in zip(e, cov, strict=True)])
                f = np.array([100, 100, math.degrees(1)])
                rms = lambda a: np.sqrt(np.mean(a * a, axis=0))  # noqa: E731
                er, sr, zr = rms(e) * f, rms(sig) * f, rms(z)
                print(f"{sname:>16} {len(sel):4d} {which:>6} {model:>14} | "
                      f"{er[0]:5.2f} {er[1]:5.2f} {er[2]:5.2f} | "
                      f"{sr[0]:5.2f} {sr[1]:5.2f} {sr[2]:5.2f} | "
                      f"{zr[0]:4.2f} {zr[1]:4.2f} {zr[2]:4.2f} | "
                      f"{100 * np.mean(np.abs(z) > 2):5.1f} {100 * np.mean(np.abs(z) > 3):5.1f} | "
                      f"{np.mean(nees):6.1f}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--logs", default="freiburg,edmonton")
    ap.add_argument("--variants", default="")
    ap.add_argument("--mapper-covariance", choices=["residual", "olson"], default=None,
                    help="the covariance the mapper fuses (default: the configuration's)")
    ap.add_argument("--mapper-spread", choices=["off", "heading", "full"], default=None,
                    help="the submap uncertainty the mapper adds (default: the configuration's)")
    ap.add_argument("--reference-check", action="store_true")
    args = ap.parse_args()
    runs = [(LOGS[n], 1, 1.0) for n in args.logs.split(",") if n in LOGS]
    for v in (v for v in args.variants.split(",") if v):
        if v in HELD_OUT:
            print(f"{v} is held out: not looked at here", file=sys.stderr)
            return 2
        fname, every, factor, *rev = VARIANTS[v]
        if rev and rev[0]:
            print(f"{v}: reversed variants are held out", file=sys.stderr)
            return 2
        runs.append((fname, every, factor))
    cfg = MappingConfig(final_pass=True)
    if args.mapper_covariance:
        cfg = replace(cfg, submap_cfg=replace(cfg.submap_cfg,
                                              covariance=args.mapper_covariance))
    if args.mapper_spread:
        cfg = replace(cfg, submap_spread=args.mapper_spread)
    print(f"mapper fuses the {cfg.submap_cfg.covariance} covariance, submap spread "
          f"{cfg.submap_spread}")
    for fname, every, factor in runs:
        log = read_log(CARMEN / fname)
        pts = scan_points(log)[::every]
        ref = np.array([s.pose for s in log.scans])[::every]
        ref = np.array([relative(ref[0], p) for p in ref])
        rows, ates = [], []
        for seed in range(args.seeds):
            m = TracingMapper(cfg)
            for o, p in zip(drifting_odometry(ref, seed, odometry_errors(factor)), pts,
                            strict=True):
                m.add_scan(o, p)
            ates.append(ate_m(m.finish(), ref))
            rows += score(m.trace, ref, cfg)
        report(f"{fname} every {every} x{factor:g} seeds 0..{args.seeds - 1}", rows)
        print("ATE m per seed: " + " ".join(f"{a:.3f}" for a in ates))
        if args.reference_check:
            reference_check(pts, ref, cfg)
    return 0


if __name__ == "__main__":
    sys.exit(main())
