"""``any_angle`` on fresh Moving AI draws: for each seed, 60 scenario queries
drawn with ``default_rng(1000 + seed)`` (draws the bench and the tuning never
used), those up to --max-len cells checked against the true shortest path
(visibility graph over the convex corners, bench/_visgraph.py); prints per map
how many are over 1.01×, the worst four, and the CPU time per query (all
queries, time.process_time).

Seeds draw from the same scenario file, so they share queries (random512's
1780 hold few long ones: seeds 21–40 repeat 2/3 of their draws). With
--exclude-seeds the queries those seeds draw are left out and every query
counts once — a held-out set disjoint from the tuning seeds:

    .venv/bin/python bench/fws_fresh.py --maps den520d,random512-20-0 --seeds 13-20
    .venv/bin/python bench/fws_fresh.py --seeds 21-40 --exclude-seeds 0-20

The true lengths are kept in --cache (a pickle per map and length limit), so a
second run with other settings costs only the planning.
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
sys.path.insert(0, str(ROOT / "bench"))

from _visgraph import convex_corners, true_shortest  # noqa: E402

from app.core.planner import any_angle, load_movingai_map, load_movingai_scen  # noqa: E402


def draws(movingai: Path, name: str, seed: int, k: int = 60):
    qs = load_movingai_scen(movingai / "scen" / f"{name}.map.scen")
    idx = np.random.default_rng(1000 + seed).choice(len(qs), size=min(k, len(qs)),
                                                    replace=False)
    return [(tuple(qs[i].start), tuple(qs[i].goal)) for i in idx]


def run_map(movingai: Path, name: str, seeds: list[int], max_len: float, cache: Path,
            exclude: list[int] = ()) -> None:
    g = np.ascontiguousarray(load_movingai_map(movingai / "maps" / f"{name}.map").blocked,
                             dtype=np.uint8)
    f = cache / f"fws_fresh_{name}_{max_len:g}.pkl"
    truth = pickle.loads(f.read_bytes()) if f.exists() else {}
    corners = None
    ratios, ms = [], []
    skip = {q for seed in exclude for q in draws(movingai, name, seed)}
    for seed in seeds:
        for s, t in draws(movingai, name, seed):
            if exclude:
                if (s, t) in skip:
                    continue
                skip.add((s, t))
            c0 = time.process_time()
            r = any_angle(g, s, t)
            ms.append((time.process_time() - c0) * 1e3)
            if (s, t) not in truth:
                if not r.found or r.length > max_len:
                    truth[(s, t)] = None
                else:
                    if corners is None:
                        corners = np.array(convex_corners(g), dtype=np.int64).reshape(-1, 2)
                    truth[(s, t)] = true_shortest(g, s, t, corners, r.length)
            if truth[(s, t)]:
                ratios.append((r.length / truth[(s, t)], seed, s, t))
        f.write_bytes(pickle.dumps(truth))
    ratios.sort(reverse=True)
    over = sum(1 for x in ratios if x[0] > 1.01)
    worst = ", ".join(f"{q:.4f} (seed {sd}, {s}->{t})" for q, sd, s, t in ratios[:4])
    print(f"{name}: {len(ratios)} checked (≤ {max_len:g} cells), over 1.01: {over}; "
          f"worst {worst}")
    print(f"    CPU per query over {len(ms)}: median {np.median(ms):.2f} ms, "
          f"p95 {np.percentile(ms, 95):.2f} ms")


def _seeds(text: str) -> list[int]:
    """A range a-b or a list a,b,c."""
    if "-" in text:
        lo, hi = (int(v) for v in text.split("-"))
        return list(range(lo, hi + 1))
    return [int(v) for v in text.split(",")]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--maps", default="den520d,random512-20-0,32room_000,maze-400-4")
    ap.add_argument("--seeds", default="13-20", help="a range a-b or a list a,b,c")
    ap.add_argument("--exclude-seeds", default="",
                    help="leave out the queries these seeds draw; count each query once")
    ap.add_argument("--max-len", type=float, default=220.0)
    ap.add_argument("--movingai", type=Path, default=ROOT.parent / "shared" / "movingai")
    ap.add_argument("--cache", type=Path, default=Path("/tmp"))
    a = ap.parse_args(argv)
    seeds = _seeds(a.seeds)
    exclude = _seeds(a.exclude_seeds) if a.exclude_seeds else []
    any_angle(np.zeros((4, 4), np.uint8), (0, 0), (3, 3))  # load the compiled kernels
    for name in a.maps.split(","):
        run_map(a.movingai, name, seeds, a.max_len, a.cache, exclude)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
