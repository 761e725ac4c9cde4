"""How far the laser mapper's loop edges are off, and why (issue 13).

    python bench/loop_edge_errors.py --log edmonton --seeds 0,3
    python bench/loop_edge_errors.py --variant edmonton-every2 --seeds 8,15
    python bench/loop_edge_errors.py --variant edmonton-every2 --seeds 8,15 \
        --method full-finalwin0 --no-rematch   # another bench method; edges only

Runs the "full" method of bench/localisation_bench.py (MappingConfig with
the final pass, the long-range ties and the edge reweighting) on a tuning
log or a tuning variant with the same raw-like odometry draws, keeps the
final graph and scores each loop edge against the reference: the error of
its measured pose z (translation, heading), the error in σ of its stated
(reweighted) covariance, and its pull after the solve (the Cauchy weight),
per origin: closures found while driving ("online"), the final pass's
("final") and the long-range ties ("ties"), and by the path they span.

Then the final pass's edges are matched again as the pass matches them (the
grid fit on a submap of the old landmark and its neighbours, no search) but
with the keyframes at their *reference* poses, from the reference pose: what
the matcher alone errs when the submap is exact. With the submap made of the
old landmark's scan alone ("single") and of its neighbours (``--neighbours``,
as the pass). The gap between these and the edges' own error is what the
solved poses' errors in the submap add.
Held-out variants are refused.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import app.core.localisation.mapping as mapping_mod  # noqa: E402
from app.core.localisation.carmen import read_log  # noqa: E402
from app.core.localisation.evaluate import ate_m, drifting_odometry  # noqa: E402
from app.core.localisation.mapping import LaserMapper, MappingConfig  # noqa: E402
from app.core.localisation.se2 import relative, wrap  # noqa: E402
from app.core.localisation.slam import scan_points  # noqa: E402
from app.core.localisation.submap_match import Submap, SubmapConfig, match_submap  # noqa: E402
from bench.localisation_bench import (  # noqa: E402
    CARMEN,
    VARIANTS,
    method_config,
    odometry_errors,
    variant_indices,
)

HELD_OUT = {"edmonton-harsh", "edmonton-reversed", "edmonton-every2-odd-x1.25",
            "edmonton-every2-reversed-x1", "edmonton-every2-odd-x1.75",
            "edmonton-reversed-3passes-x1.25", "edmonton-every2-x1.5"}
LOGS = {"edmonton": "edmonton-corrected.log.gz", "freiburg": "freiburg-101-corrected.log.gz"}


def load(log: str | None, variant: str | None):
    if variant:
        if variant in HELD_OUT:
            raise SystemExit(f"{variant} is held out")
        fname, every, factor, *extra = VARIANTS[variant]
        back = bool(extra and extra[0])
        offset = int(extra[1]) if len(extra) > 1 else 0
        passes = int(extra[2]) if len(extra) > 2 else 1
    else:
        fname, every, factor, back, offset, passes = LOGS[log], 1, 1.0, False, 0, 1
    data = read_log(CARMEN / fname)
    idx = variant_indices(len(data.scans), every, back, offset, passes)
    allp = scan_points(data)
    ref = np.array([s.pose for s in data.scans])[idx]
    ref = np.array([relative(ref[0], p) for p in ref])
    return [allp[i] for i in idx], ref, factor


def run(pts, odo, cfg: MappingConfig):
    """The mapper's final graph and the (old, new) pairs of the final pass's
    edges and of the long-range ties."""
    tagged: dict[str, set] = {"final": set(), "ties": set()}
    fp, lr = mapping_mod.final_pass, mapping_mod.long_range_ties

    def final_pass(*a, **k):
        out = fp(*a, **k)
        tagged["final"] |= {(c.old, c.new) for c in out}
        return out

    def long_range_ties(*a, **k):
        out = lr(*a, **k)
        tagged["ties"] |= {(c.old, c.new) for c in out}
        return out

    mapping_mod.final_pass, mapping_mod.long_range_ties = final_pass, long_range_ties
    try:
        m = LaserMapper(cfg)
        for o, p in zip(odo, pts, strict=True):
            m.add_scan(o, p)
        est = m.finish()
    finally:
        mapping_mod.final_pass, mapping_mod.long_range_ties = fp, lr
    return m, est, tagged


def edge_rows(m, est, ref, tagged, path_m):
    rows = []
    for e in m.edges:
        if not e.loop:
            continue
        kind = ("final" if (e.i, e.j) in tagged["final"] else
                "ties" if (e.i, e.j) in tagged["ties"] else "online")
        truth = relative(ref[e.i], ref[e.j])
        err = e.z - truth
        err[2] = float(wrap(err[2]))
        res = relative(est[e.i], est[e.j]) - e.z
        res[2] = float(wrap(res[2]))
        rows.append((kind, abs(path_m[e.j] - path_m[e.i]), math.hypot(err[0], err[1]),
                     abs(math.degrees(err[2])), float(np.linalg.norm(e.sqrt_info @ err)),
                     float(np.linalg.norm(e.sqrt_info @ res)), e.i, e.j))
    return rows


MATCHERS = ("grid", "grid-fine", "icp", "icp-faces", "grid+icp")


def rematch(m, ref, pts, pairs, neighbours: int, seed: int = 0):
    """The final pass's matches again with the keyframes at the reference
    poses, from the reference pose moved by 5 cm / 0.5° (random): per pair and
    per matcher of ``MATCHERS`` (the grid fit on the single old scan and on
    the old scan ± ``neighbours``, then each matcher on the latter) the
    translation (m) and heading (deg) errors."""
    from app.core.localisation.icp import IcpConfig, icp, stacked_reference
    from app.core.localisation.se2 import compose
    rng = np.random.default_rng(seed)
    nodes = [lm.node for lm in m.landmarks]
    pos = {n: k for k, n in enumerate(nodes)}
    fine = SubmapConfig(res_m=0.025, sigma_m=0.04)
    icfg = IcpConfig()
    out = []
    for old, new in pairs:
        if old not in pos:
            continue
        k = pos[old]
        a = rng.uniform(0, 2 * math.pi)
        start = compose(ref[new], np.array([0.05 * math.cos(a), 0.05 * math.sin(a),
                                            math.radians(0.5) * rng.choice([-1, 1])]))
        poses = []
        add = poses.append
        one = Submap([(ref[m.landmarks[k].node], m.landmarks[k].points)], SubmapConfig())
        add(match_submap(pts[new], one, start, cov_half_steps=4).pose)
        group = m.landmarks[max(0, k - neighbours):k + neighbours + 1]
        sub = Submap([(ref[lm.node], lm.points) for lm in group], SubmapConfig())
        r = match_submap(pts[new], sub, start, cov_half_steps=4)
        add(r.pose)
        subf = Submap([(ref[lm.node], lm.points) for lm in group], fine)
        add(match_submap(pts[new], subf, start, cov_half_steps=4).pose)
        scans = [(ref[lm.node], lm.points, lm.normals, lm.planar) for lm in group]
        refi = stacked_reference(scans, icfg.normal_neighbours, icfg.bucket_m)
        add(icp(pts[new], refi, start, icfg).pose)
        reff = stacked_reference(scans, icfg.normal_neighbours, icfg.bucket_m, faces=True)
        add(icp(pts[new], reff, start, icfg).pose)
        add(icp(pts[new], refi, r.pose, icfg).pose)
        errs = []
        for p in poses:
            d = relative(ref[new], p)
            errs += [math.hypot(d[0], d[1]), abs(math.degrees(float(wrap(d[2]))))]
        out.append(errs)
    return np.array(out)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--log", default="edmonton", choices=sorted(LOGS))
    ap.add_argument("--variant", default="")
    ap.add_argument("--seeds", default="0")
    ap.add_argument("--neighbours", type=int, default=2)
    ap.add_argument("--method", default="full",
                    help="a method of bench/localisation_bench.py (default full)")
    ap.add_argument("--no-rematch", action="store_true",
                    help="skip matching the final pass's edges again on the reference poses")
    args = ap.parse_args()
    pts, ref, factor = load(args.log, args.variant or None)
    path_m = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(ref[:, :2], axis=0).T))))
    for seed in (int(s) for s in args.seeds.split(",")):
        odo = drifting_odometry(ref, seed, odometry_errors(factor))
        m, est, tagged = run(pts, odo, method_config(args.method))
        rows = edge_rows(m, est, ref, tagged, path_m)
        print(f"\n{args.variant or args.log} draw {seed}: ATE {ate_m(est, ref):.3f} m, "
              f"{len(rows)} loop edges")
        print(f"{'origin':>7} {'span m':>9} | {'n':>4} | {'err cm':>6} {'deg':>5} | "
              f"{'rms σ':>5} | {'>15 cm':>6} | {'resid σ':>7}")
        kinds = np.array([r[0] for r in rows])
        a = np.array([r[1:6] for r in rows], float)
        for kind in ("online", "final", "ties"):
            for lo, hi in ((0, 15), (15, 60), (60, 1e9)):
                sel = (kinds == kind) & (a[:, 0] >= lo) & (a[:, 0] < hi)
                if not sel.any():
                    continue
                b = a[sel]
                print(f"{kind:>7} {lo:>3.0f}-{hi if hi < 1e8 else 'inf':>5} | {sel.sum():4d} | "
                      f"{100 * b[:, 1].mean():6.1f} {b[:, 2].mean():5.2f} | "
                      f"{math.sqrt(np.mean(b[:, 3] ** 2)):5.2f} | {np.sum(b[:, 1] > 0.15):6d} | "
                      f"{np.mean(b[:, 4]):7.2f}")
        worst = sorted(rows, key=lambda r: -r[2])[:8]
        print("worst: " + "; ".join(f"{r[0]} {r[6]}->{r[7]} {100 * r[2]:.0f} cm "
                                    f"{r[3]:.1f} deg" for r in worst))
        fin = [(r[6], r[7]) for r in rows if r[0] == "final"]
        rm = [] if args.no_rematch else rematch(m, ref, pts, fin, args.neighbours)
        ferr = a[kinds == "final"]
        if len(rm):
            print(f"final-pass edges ({len(fin)}): as kept {100 * ferr[:, 1].mean():.1f} cm "
                  f"{ferr[:, 2].mean():.2f} deg; matched again on the reference poses:")
            for c, name in enumerate(("grid, single scan",) + MATCHERS):
                print(f"  {name:>18}: {100 * rm[:, 2 * c].mean():5.1f} cm "
                      f"(median {100 * np.median(rm[:, 2 * c]):4.1f}) "
                      f"{rm[:, 2 * c + 1].mean():.2f} deg")
    return 0


if __name__ == "__main__":
    sys.exit(main())
