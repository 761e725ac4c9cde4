"""The TEB's analytic Jacobian against forward differences, on recorded problems.

    PYTHONPATH=$PWD .venv/bin/python bench/teb_jacobian_bench.py
        [--cache /tmp/teb_problems.pkl] [--record] [--record-with fd] [--limit 0]

Records every problem the TEB solver is handed during the 4WS crowd patrol
(tests/sim/test_fws_patrol.py's run: default route, gauges dwelling 50 s, six
crossing workers, seed 7) — the start band z0 and the arguments, moving
obstacles' discs included — into --cache (once; --record records again; the
patrol's TEB runs with --record-with's Jacobian, forward differences as before
by default), then
for each problem, with ``TebConfig.jacobian`` "fd" and "analytic":

- CPU per Jacobian (``Teb._jacobian_values`` at z0, best of 5 calls);
- CPU per solve (``Teb._solve`` from z0, the default banded LM, 12 function
  evaluations) and its final cost;
- the largest difference between the two Jacobians, relative to the largest
  entry of the row (forward differences err by ~1e-6 relative, more at kinks).

All times are CPU time (time.process_time) on a shared machine.
"""

from __future__ import annotations

import argparse
import pickle
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from app.core.planner.teb import Teb, TebConfig  # noqa: E402


def record(cache: Path, jacobian: str) -> None:
    import importlib.util
    from dataclasses import replace

    from sim_robot.config import SimConfig
    from sim_robot.fws_robot import FwsOfflinePatrol
    from sim_robot.route import DEFAULT_ROUTE, load_route

    spec = importlib.util.spec_from_file_location("patrol_bench",
                                                  ROOT / "bench" / "patrol_bench.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    problems = []
    solve = Teb._solve

    def recording(self, z0, args):
        if self.cfg.jacobian != jacobian:
            self.cfg = replace(self.cfg, jacobian=jacobian)
        problems.append((self.cfg, z0.copy(), args))
        return solve(self, z0, args)

    Teb._solve = recording
    try:
        route = load_route(DEFAULT_ROUTE)
        for p in route.points:
            if p.gauge:
                p.dwell_s = 50.0
        op = FwsOfflinePatrol(SimConfig(seed=7, video=False))
        mod.add_crowd(op.world, 6, 7)
        print("patrol:", op.run(route, max_sim_s=1800))
    finally:
        Teb._solve = solve
    with open(cache, "wb") as f:
        pickle.dump(problems, f)
    print(f"recorded {len(problems)} problems into {cache}")


def cpu_ms(fn, reps=1):
    best = float("inf")
    for _ in range(reps):
        t = time.process_time()
        out = fn()
        best = min(best, time.process_time() - t)
    return out, best * 1e3


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", type=Path, default=Path("/tmp/teb_problems.pkl"))
    ap.add_argument("--record", action="store_true")
    ap.add_argument("--record-with", choices=("fd", "analytic"), default="fd",
                    help="the Jacobian the patrol's TEB uses while recording")
    ap.add_argument("--limit", type=int, default=0, help="use the first N problems (0: all)")
    args = ap.parse_args(argv)
    if args.record or not args.cache.exists():
        record(args.cache, args.record_with)
    with open(args.cache, "rb") as f:
        problems = pickle.load(f)
    if args.limit:
        problems = problems[: args.limit]
    jac_ms = {"fd": [], "analytic": []}
    solve_ms = {"fd": [], "analytic": []}
    cost = {"fd": [], "analytic": []}
    rel_err, sizes = [], []
    for cfg0, z0, a in problems:
        tebs = {k: Teb(TebConfig(**{**cfg0.__dict__, "jacobian": k})) for k in jac_ms}
        n = a[0]
        sizes.append(n)
        vals = {}
        for k, teb in tebs.items():
            teb._solve(z0, a)  # warm the pattern caches
            r = teb._residuals(z0, *a)
            vals[k], t = cpu_ms(lambda teb=teb, r=r, z0=z0, a=a: teb._jacobian_values(z0, r, *a), 5)
            jac_ms[k].append(t)
        rows = tebs["fd"]._sparsity(n, a[4] is not None)[0]
        scale = np.zeros(rows.max() + 1)
        np.maximum.at(scale, rows, np.maximum(np.abs(vals["analytic"]), np.abs(vals["fd"])))
        d = np.abs(vals["analytic"] - vals["fd"]) / np.maximum(scale[rows], 1e-9)
        rel_err.append(float(np.max(d)))
        for k, teb in tebs.items():
            sol, t = cpu_ms(lambda teb=teb, z0=z0, a=a: teb._solve(z0, a))
            solve_ms[k].append(t)
            cost[k].append(float(sol.cost))
    sizes = np.array(sizes)
    print(f"{len(problems)} problems, band {sizes.min()}–{sizes.max()} poses "
          f"(median {int(np.median(sizes))})")
    print(f"{'Jacobian':10} {'jac med ms':>10} {'jac p90':>8} {'solve med ms':>12} "
          f"{'solve p90':>9} {'solve total s':>13}")
    for k in jac_ms:
        j, s = np.array(jac_ms[k]), np.array(solve_ms[k])
        print(f"{k:10} {np.median(j):>10.3f} {np.percentile(j, 90):>8.3f} "
              f"{np.median(s):>12.2f} {np.percentile(s, 90):>9.2f} {s.sum() / 1e3:>13.2f}")
    ratio = np.array(cost["analytic"]) / np.maximum(np.array(cost["fd"]), 1e-12)
    print(f"final cost analytic / fd: median {np.median(ratio):.3f}, "
          f"p10 {np.percentile(ratio, 10):.3f}, p90 {np.percentile(ratio, 90):.3f}, "
          f"over 2x: {np.mean(ratio > 2) * 100:.1f} %, "
          f"under 0.5x: {np.mean(ratio < 0.5) * 100:.1f} %")
    print(f"final cost summed over the problems: fd {np.sum(cost['fd']):.1f}, "
          f"analytic {np.sum(cost['analytic']):.1f}; geometric mean of the ratio "
          f"{np.exp(np.mean(np.log(np.maximum(ratio, 1e-12)))):.3f}")
    e = np.array(rel_err)
    print(f"|analytic − fd| / row max: median {np.median(e):.1e}, p90 {np.percentile(e, 90):.1e}, "
          f"max {e.max():.1e}; problems over 1e-3 (a hinge or cell edge within the "
          f"1e-6 step): {np.sum(e > 1e-3)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
