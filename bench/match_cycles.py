"""Is the grid matcher off, or the reference? Cycles of matches (issue 13).

    python bench/match_cycles.py --log edmonton
    python bench/match_cycles.py --log freiburg

bench/loop_edge_errors.py found that the submap matcher, given a submap
drawn at the *reference* poses, lands 5–6 cm from the reference pose on
edmonton. The reference is itself an estimate (the logs' "corrected"
trajectories come from another SLAM run), so that figure mixes the
matcher's error with the reference's. A cycle of matches separates them:
for consecutive scans a, b, c each scan is matched on a submap of one
earlier scan alone (submap_match.match_submap, the grid fit, no search),
from its reference pose moved 5 cm / 0.5°, giving z_ab, z_bc, z_ac; the
cycle z_ab ⊕ z_bc ⊖ z_ac involves no reference at all. Were each match off
by independent errors of the size it disagrees with the reference, the
cycle would be √3 times that; a cycle much smaller says the matches agree
with one another and the disagreement is the reference's (or a per-scan
distortion every match of that scan shares).

Per match (mean translation / heading over the log): disagreement with
the reference, the cycle's residual, and the split this implies (e_m the
matcher's own error per match ≈ cycle / √3, e_r the reference's per pose
≈ √((d² − e_m²) / 2), means treated as rms). Reads only tuning logs.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from app.core.localisation.carmen import read_log  # noqa: E402
from app.core.localisation.se2 import compose, relative, wrap  # noqa: E402
from app.core.localisation.slam import scan_points  # noqa: E402
from app.core.localisation.submap_match import Submap, SubmapConfig, match_submap  # noqa: E402
from bench.localisation_bench import CARMEN  # noqa: E402

LOGS = {"edmonton": "edmonton-corrected.log.gz", "freiburg": "freiburg-101-corrected.log.gz"}


def cycles(pts, ref, seed: int = 0, jitter: bool = True):
    """Per triple (a, a+1, a+2): the three matches' errors against the
    reference and the cycle's residual, each (translation m, heading deg)."""
    rng = np.random.default_rng(seed)
    cfg = SubmapConfig()

    def z(a: int, b: int):
        truth = relative(ref[a], ref[b])
        start = truth
        if jitter:
            ang = rng.uniform(0, 2 * math.pi)
            start = compose(truth, np.array([0.05 * math.cos(ang), 0.05 * math.sin(ang),
                                             math.radians(0.5) * rng.choice([-1, 1])]))
        sub = Submap([(np.zeros(3), pts[a])], cfg)
        return match_submap(pts[b], sub, start, cov_half_steps=4).pose, truth

    def err(d):
        return math.hypot(d[0], d[1]), abs(math.degrees(float(wrap(d[2]))))

    errs, cyc = [], []
    for a in range(len(pts) - 2):
        z01, t01 = z(a, a + 1)
        z12, t12 = z(a + 1, a + 2)
        z02, t02 = z(a, a + 2)
        errs += [err(relative(t, m)) for m, t in ((z01, t01), (z12, t12), (z02, t02))]
        cyc.append(err(relative(compose(z01, z12), z02)))
    return np.array(errs), np.array(cyc)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--log", default="edmonton", choices=sorted(LOGS))
    args = ap.parse_args()
    data = read_log(CARMEN / LOGS[args.log])
    pts = scan_points(data)
    ref = np.array([s.pose for s in data.scans])
    for jitter in (True, False):
        e, c = cycles(pts, ref, jitter=jitter)
        em = c[:, 0].mean() / math.sqrt(3)
        er = math.sqrt(max(e[:, 0].mean() ** 2 - em ** 2, 0.0) / 2)
        print(f"{args.log}, start {'5 cm / 0.5 deg off' if jitter else 'at the reference'}: "
              f"{len(c)} cycles; matches vs reference {100 * e[:, 0].mean():.1f} cm "
              f"(median {100 * np.median(e[:, 0]):.1f}) {e[:, 1].mean():.2f} deg; cycle "
              f"{100 * c[:, 0].mean():.1f} cm (median {100 * np.median(c[:, 0]):.1f}) "
              f"{c[:, 1].mean():.2f} deg, {100 * math.sqrt(3) * e[:, 0].mean():.1f} cm if "
              f"independent; implied matcher {100 * em:.1f} cm per match, reference "
              f"{100 * er:.1f} cm per pose; matches one / two scans apart vs reference "
              f"{100 * e[0::3, 0].mean():.1f} / {100 * e[2::3, 0].mean():.1f} cm")
    return 0


if __name__ == "__main__":
    sys.exit(main())
