"""Does the CARMEN reader's sensor model fit a log's reference? (issue 13)

    python bench/sensor_model_check.py --log edmonton
    python bench/sensor_model_check.py --log freiburg

Each scan is matched on a submap of the scan before it alone (the grid fit
of submap_match.py, searched from the reference's relative pose moved
5 cm / 0.5°), with the beams at the reader's bearings (carmen.py
``beam_angles``) and at wrong ones: the bearings' increment 0.5 % or 1 %
too large or small, a 181-beam log's convention (the field's ends
included) and bearings half a step off. Per model, the matches' heading
error against the reference: its mean and rms, the regression on the turn
between the scans (a slope is a turn-gain error of the matches: a wrong
increment stretches every bearing, so a turn of Δθ is matched as
(1 + ε) Δθ) and the mean on left turns, right turns and straights. Then,
with the reader's bearings, the laser offset (forward, left) from the
reference poses that best explains the matches' position errors (a laser
ahead of the pose it is drawn at moves sideways on a turn). The reference
is another SLAM's estimate; the check says whether the model and the
reference agree, not which is right.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from app.core.localisation.carmen import read_log  # noqa: E402
from app.core.localisation.preprocess import preprocess  # noqa: E402
from app.core.localisation.se2 import compose, relative, wrap  # noqa: E402
from app.core.localisation.submap_match import Submap, SubmapConfig, match_submap  # noqa: E402
from bench.localisation_bench import CARMEN  # noqa: E402

LOGS = {"edmonton": "edmonton-corrected.log.gz", "freiburg": "freiburg-101-corrected.log.gz"}


def step_matches(pts, ref, seed: int = 0) -> np.ndarray:
    """Per scan b ≥ 1: (reference step x, y, θ, match error x, y, θ), the
    error in the reference step's frame."""
    rng = np.random.default_rng(seed)
    out = []
    for b in range(1, len(pts)):
        truth = relative(ref[b - 1], ref[b])
        ang = rng.uniform(0, 2 * math.pi)
        start = compose(truth, np.array([0.05 * math.cos(ang), 0.05 * math.sin(ang),
                                         math.radians(0.5) * rng.choice([-1, 1])]))
        sub = Submap([(np.zeros(3), pts[b - 1])], SubmapConfig())
        d = relative(truth, match_submap(pts[b], sub, start, cov_half_steps=2).pose)
        out.append((*truth, d[0], d[1], float(wrap(d[2]))))
    return np.array(out)


def laser_offset(m: np.ndarray) -> np.ndarray:
    """The offset o (forward, left) of the laser from the reference poses
    that best explains the matches' position errors: the laser's step is
    o⁻¹ ⊕ step ⊕ o."""
    def pred(o):
        oo = np.array([o[0], o[1], 0.0])
        return np.array([relative(t, compose(relative(oo, t), oo))[:2] for t in m[:, :3]])
    return least_squares(lambda o: (pred(o) - m[:, 3:5]).ravel(), [0.0, 0.0]).x


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--log", default="edmonton", choices=sorted(LOGS))
    args = ap.parse_args()
    log = read_log(CARMEN / LOGS[args.log])
    ref = np.array([s.pose for s in log.scans])
    n = log.scans[0].ranges_m.size
    base = log.beam_angles(n)
    no_return = log.no_return_m()
    models = {"as read": base, "increment x1.005": base * 1.005,
              "increment x0.995": base * 0.995, "increment x1.01": base * 1.01,
              "increment x0.99": base * 0.99,
              "field's ends included": np.linspace(base[0], -base[0], n),
              "half a step on": base + (base[1] - base[0]) / 2}
    print(f"{args.log}: {len(ref)} scans, {n} beams; heading error of each scan's match "
          "against the reference (deg)")
    for label, angles in models.items():
        pts = [preprocess(s.ranges_m, angles, None, no_return) for s in log.scans]
        m = step_matches(pts, ref)
        turn, e = np.degrees(m[:, 2]), np.degrees(m[:, 5])
        slope, icpt = np.linalg.lstsq(np.c_[turn, np.ones_like(turn)], e, rcond=None)[0]
        left, right, straight = turn > 5, turn < -5, np.abs(turn) <= 5
        print(f"{label:>22}: mean {e.mean():+.3f} (±{e.std() / math.sqrt(len(e)):.3f}), rms "
              f"{np.sqrt(np.mean(e ** 2)):.3f}; slope on the turn {100 * slope:+.2f} %; "
              f"left / right / straight {e[left].mean():+.3f} / {e[right].mean():+.3f} / "
              f"{e[straight].mean():+.3f} ({left.sum()} / {right.sum()} / {straight.sum()}); "
              f"position error {100 * np.hypot(m[:, 3], m[:, 4]).mean():.1f} cm")
        if label == "as read":
            o = laser_offset(m)
            print(f"{'':>22}  laser offset that fits the matches best: forward "
                  f"{100 * o[0]:+.1f} cm, left {100 * o[1]:+.1f} cm (PARAM "
                  f"robot_frontlaser_offset {log.laser_offset_m[0]:+.2f} m, not applied)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
