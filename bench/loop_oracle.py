"""Where a failing map's error lies and which edges it comes from (issue 13).

    python bench/loop_oracle.py --variant edmonton-every2 --seeds 8,15
    python bench/loop_oracle.py --log edmonton --seeds 0

Runs the "full" method of bench/localisation_bench.py on a tuning log or
variant (held-out variants are refused, as in bench/loop_edge_errors.py),
keeps the final graph and, against the reference (diagnosis only; the
mapper never sees it):

- the error profile: each node's position and heading error after a rigid
  alignment on the middle of the path (nodes in the middle ``--middle``
  fraction of the path), so that a stretch turned as a block shows as a
  growing heading error;
- oracle re-solves of the kept graph: the loop edges stating more than 3 or
  4 σ of error dropped; each class of edges (steps, online closures, final
  pass, long-range ties) given its exact measurement (the reference's
  relative pose, same covariance); each class of loop edges removed. What
  the ATE becomes says which edges hold the error, and whether a few wrong
  ones (dropping) or the many slightly wrong ones (exact) do.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from app.core.localisation.evaluate import ate_m, drifting_odometry  # noqa: E402
from app.core.localisation.pose_graph import Edge, solve_pose_graph  # noqa: E402
from app.core.localisation.se2 import relative, wrap  # noqa: E402
from bench.localisation_bench import method_config, odometry_errors  # noqa: E402
from bench.loop_edge_errors import load, run  # noqa: E402


def profile(est: np.ndarray, ref: np.ndarray, sel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Position (m) and heading (deg) error of every node after the rigid
    alignment of the nodes ``sel`` onto the reference."""
    a, b = est[sel, :2], ref[sel, :2]
    ma, mb = a.mean(0), b.mean(0)
    u, _, vt = np.linalg.svd((b - mb).T @ (a - ma))
    rot = u @ np.diag([1, np.sign(np.linalg.det(u @ vt))]) @ vt
    al = (est[:, :2] - ma) @ rot.T + mb
    th = math.atan2(rot[1, 0], rot[0, 0])
    return np.hypot(*(al - ref[:, :2]).T), np.degrees(wrap(est[:, 2] + th - ref[:, 2]))


def exact_step(e: Edge, ref: np.ndarray, parts: str) -> Edge:
    """A step edge with the reference's value in ``parts``: "h" its heading,
    "a" / "c" its translation along / across the reference's motion."""
    t = relative(ref[e.i], ref[e.j])
    z = np.array(e.z, float)
    u = t[:2] / max(math.hypot(t[0], t[1]), 1e-9)
    for key, d in (("a", u), ("c", np.array([-u[1], u[0]]))):
        if key in parts:
            z[:2] -= d * float((z[:2] - t[:2]) @ d)
    if "h" in parts:
        z[2] = t[2]
    return Edge(e.i, e.j, z, e.sqrt_info, e.loop)


def unclosed_runs(edges: list[Edge], n: int, min_nodes: int = 5) -> list[tuple[int, int]]:
    """(first, last) of each run of at least ``min_nodes`` consecutive nodes
    that no loop edge touches."""
    touched = np.zeros(n, bool)
    for e in edges:
        if e.loop:
            touched[[e.i, e.j]] = True
    runs, start = [], None
    for k in range(n + 1):
        if k < n and not touched[k]:
            start = k if start is None else start
        elif start is not None:
            if k - start >= min_nodes:
                runs.append((start, k - 1))
            start = None
    return runs


def steps_oracle(edges: list[Edge], ref: np.ndarray, ate, stretch: int) -> None:
    steps = [e for e in edges if not e.loop]
    out = []
    for parts, name in (("h", "heading"), ("ac", "translation"), ("a", "along")):
        fixed = [exact_step(e, ref, parts) if not e.loop else e for e in edges]
        out.append(f"{name} {ate(fixed):.3f}")
    print("  steps exact in their " + ", ".join(out) + " (ATE m)")
    n = len(ref)
    out = []
    for lo in range(0, n - 1, stretch):
        fixed = [exact_step(e, ref, "ach") if not e.loop and lo < e.j <= lo + stretch else e
                 for e in edges]
        out.append(f"{lo}-{min(lo + stretch, n - 1)}: {ate(fixed):.3f}")
    print("  steps exact by stretch, ATE m: " + "; ".join(out))
    for a, b in unclosed_runs(edges, n):
        run_steps = [e for e in steps if a < e.j <= b]
        err = sum(float(wrap(e.z[2] - relative(ref[e.i], ref[e.j])[2])) for e in run_steps)
        sd = math.sqrt(sum(float(np.linalg.inv(e.sqrt_info.T @ e.sqrt_info)[2, 2])
                           for e in run_steps))
        print(f"  nodes {a}-{b} touched by no loop edge: steps' heading error sums to "
              f"{math.degrees(err):+.2f} deg, stated sigma {math.degrees(sd):.2f} deg")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--log", default="edmonton", choices=("edmonton", "freiburg"))
    ap.add_argument("--variant", default="")
    ap.add_argument("--seeds", default="8")
    ap.add_argument("--method", default="full")
    ap.add_argument("--middle", type=float, default=0.5)
    ap.add_argument("--stretch", type=int, default=20,
                    help="nodes per stretch of the steps-exact oracle (0: off)")
    args = ap.parse_args()
    pts, ref, factor = load(args.log, args.variant or None)
    n = len(ref)
    lo = int(n * (1 - args.middle) / 2)
    sel = np.arange(lo, n - lo)
    for seed in (int(s) for s in args.seeds.split(",")):
        odo = drifting_odometry(ref, seed, odometry_errors(factor))
        m, est, tagged = run(pts, odo, method_config(args.method))

        def kind(e: Edge, tagged=tagged) -> str:
            if not e.loop:
                return "step"
            return ("final" if (e.i, e.j) in tagged["final"] else
                    "ties" if (e.i, e.j) in tagged["ties"] else "online")

        def err(e: Edge) -> np.ndarray:
            d = e.z - relative(ref[e.i], ref[e.j])
            d[2] = float(wrap(d[2]))
            return d

        def ate(edges: list[Edge], est=est) -> float:
            return ate_m(solve_pose_graph(est.copy(), edges, iterations=30), ref)

        edges = m.edges
        print(f"\n{args.variant or args.log} draw {seed}: ATE {ate_m(est, ref):.3f} m "
              f"(re-solved {ate(edges):.3f})")
        pos, head = profile(est, ref, sel)
        print(f"  aligned on nodes {sel[0]}-{sel[-1]}: node cm/deg " + " ".join(
            f"{i}:{100 * pos[i]:.0f}/{head[i]:+.1f}" for i in range(0, n, 5)))
        out = []
        for thr in (3.0, 4.0):
            keep = [e for e in edges
                    if not e.loop or np.linalg.norm(e.sqrt_info @ err(e)) < thr]
            out.append(f"loop edges > {thr:.0f} σ dropped ({len(edges) - len(keep)}): "
                       f"{ate(keep):.3f}")
        for k in ("step", "online", "final", "ties"):
            exact = [Edge(e.i, e.j, relative(ref[e.i], ref[e.j]), e.sqrt_info, e.loop)
                     if kind(e) == k else e for e in edges]
            out.append(f"{k} exact: {ate(exact):.3f}")
        for k in ("online", "final", "ties"):
            out.append(f"no {k}: {ate([e for e in edges if kind(e) != k]):.3f}")
        print("  oracle re-solves, ATE m: " + "; ".join(out))
        if args.stretch > 0:
            steps_oracle(edges, ref, ate, args.stretch)
    return 0


if __name__ == "__main__":
    sys.exit(main())
