"""Where the laser mapper's 1 m relative pose error comes from (issue 13).

    python bench/rpe_situations.py --logs edmonton --seeds 3
    python bench/rpe_situations.py --logs edmonton --spread heading
    python bench/rpe_situations.py --logs edmonton --final-matcher icp

Runs the "full" method of bench/localisation_bench.py (MappingConfig with
the final pass) on the tuning logs with the same raw-like odometry draws
and splits the RPE over ``--delta`` m of path (Kümmerle et al. 2009, as
evaluate.rpe: for each scan i the first scan j at least that far on) by
situation of the pair: a big turn (the reference turns over 15° from i to
j), a corridor-like scan at j (bench/match_covariance_bench.py's test),
few points at j (under 100 after pre-processing), a scan j whose match was
refused or failed (the step stood on dead reckoning), and none of those.
Per situation: the share of pairs, the mean translation and heading error,
the error along and across the motion, and the share of the total error.
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
from app.core.localisation.evaluate import drifting_odometry  # noqa: E402
from app.core.localisation.mapping import LaserMapper, MappingConfig  # noqa: E402
from app.core.localisation.se2 import relative, wrap  # noqa: E402
from app.core.localisation.slam import scan_points  # noqa: E402
from bench.localisation_bench import CARMEN, VARIANTS, odometry_errors  # noqa: E402
from bench.match_covariance_bench import HELD_OUT, LOGS, _corridor  # noqa: E402


class CountingMapper(LaserMapper):
    """A LaserMapper that notes, per node, whether its step fused a match."""

    def __init__(self, cfg: MappingConfig) -> None:
        super().__init__(cfg)
        self.dead: list[bool] = [False]

    def add_scan(self, odom_pose, points):
        before = self.icp_failures
        out = super().add_scan(odom_pose, points)
        if len(self.dead) < len(self.poses):
            self.dead.append(self.icp_failures > before)
        return out


def pairs(est: np.ndarray, ref: np.ndarray, delta_m: float):
    """(i, j, error (x, y, θ) of the relative motion in i's frame, the
    reference motion) for every RPE pair (evaluate.rpe)."""
    path = np.r_[0.0, np.cumsum(np.hypot(*np.diff(ref[:, :2], axis=0).T))]
    for i in range(len(ref)):
        j = int(np.searchsorted(path, path[i] + delta_m))
        if j >= len(ref):
            break
        motion = relative(ref[i], ref[j])
        yield i, j, relative(motion, relative(est[i], est[j])), motion


SITUATIONS = [("big turn >15deg", lambda r: r["turn"] > math.radians(15)),
              ("corridor-like", lambda r: r["corridor"]),
              ("few points <100", lambda r: r["n"] < 100),
              ("dead reckoning", lambda r: r["dead"]),
              ("none of those", lambda r: r["turn"] <= math.radians(15) and not r["corridor"]
               and r["n"] >= 100 and not r["dead"]),
              ("all", lambda r: True)]


def report(name: str, rows: list[dict]) -> None:
    tot_t = sum(r["t"] for r in rows)
    tot_r = sum(r["r"] for r in rows)
    print(f"\n{name}: {len(rows)} pairs")
    print(f"{'situation':>16} {'pairs %':>7} | {'trans cm':>8} {'along':>6} {'across':>6} "
          f"{'deg':>5} | {'share of trans %':>16} {'of rot %':>8}")
    for sname, pick in SITUATIONS:
        sel = [r for r in rows if pick(r)]
        if not sel:
            continue
        t = np.array([r["t"] for r in sel])
        along = np.array([r["along"] for r in sel])
        across = np.array([r["across"] for r in sel])
        rot = np.array([r["r"] for r in sel])
        print(f"{sname:>16} {100 * len(sel) / len(rows):7.1f} | {100 * t.mean():8.2f} "
              f"{100 * np.abs(along).mean():6.2f} {100 * np.abs(across).mean():6.2f} "
              f"{math.degrees(rot.mean()):5.2f} | {100 * t.sum() / tot_t:16.1f} "
              f"{100 * rot.sum() / tot_r:8.1f}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--logs", default="edmonton")
    ap.add_argument("--variants", default="")
    ap.add_argument("--delta", type=float, default=1.0, help="path between a pair's scans, m")
    ap.add_argument("--spread", choices=["off", "heading", "full"], default=None,
                    help="MappingConfig.submap_spread (default: the configuration's)")
    ap.add_argument("--final-matcher", choices=["submap", "icp"], default=None,
                    help="LoopConfig.final_matcher (default: the configuration's)")
    args = ap.parse_args()
    runs = [(LOGS[n], 1) for n in args.logs.split(",") if n in LOGS]
    for v in (v for v in args.variants.split(",") if v):
        if v in HELD_OUT or len(VARIANTS[v]) > 3 or VARIANTS[v][2] != 1.0:
            print(f"{v} is held out or has other odometry errors: not here", file=sys.stderr)
            return 2
        runs.append((VARIANTS[v][0], VARIANTS[v][1]))
    cfg = MappingConfig(final_pass=True)
    if args.spread:
        cfg = replace(cfg, submap_spread=args.spread)
    if args.final_matcher:
        cfg = replace(cfg, loop=replace(cfg.loop, final_matcher=args.final_matcher))
    print(f"full method, submap spread {cfg.submap_spread}, final pass by "
          f"{cfg.loop.final_matcher}; RPE over {args.delta:g} m")
    for fname, every in runs:
        log = read_log(CARMEN / fname)
        pts = scan_points(log)[::every]
        ref = np.array([s.pose for s in log.scans])[::every]
        ref = np.array([relative(ref[0], p) for p in ref])
        corridor = [_corridor(p) for p in pts]
        rows = []
        for seed in range(args.seeds):
            m = CountingMapper(cfg)
            for o, p in zip(drifting_odometry(ref, seed, odometry_errors(1.0)), pts,
                            strict=True):
                m.add_scan(o, p)
            est = m.finish()
            for i, j, e, motion in pairs(est, ref, args.delta):
                d = math.hypot(motion[0], motion[1])
                ux, uy = (motion[0] / d, motion[1] / d) if d > 0 else (1.0, 0.0)
                rows.append({"t": math.hypot(e[0], e[1]), "r": abs(float(wrap(e[2]))),
                             "along": e[0] * ux + e[1] * uy, "across": -e[0] * uy + e[1] * ux,
                             "turn": abs(float(wrap(motion[2]))), "corridor": corridor[j],
                             "n": len(pts[j]), "dead": any(m.dead[i + 1:j + 1])})
        report(f"{fname} every {every} seeds 0..{args.seeds - 1}", rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
