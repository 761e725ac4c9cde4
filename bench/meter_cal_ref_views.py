"""How much of each reference frame's view the ``cal-ref`` row's rectification leaves.

    python bench/meter_cal_ref_views.py --seeds 11-40 [-v]

For every point's reference frame of ``bench/meter_bench.py --rows cal-ref --split tuning
--n 300 --seed S`` (``bench.meter_bench_calibrated.cal_ref_stream``, tuning families only),
the reference's geometry as the reader finds it once per file
(``calibrated._reference_geometry``) is compared with the simulator's truth: the dial's
true view at the pivot (the local linear part of the dial-to-image map, lens included)
and what is left of it through the reference's rectifier.  A view is given as the largest
error it makes in an angle about the pivot, atan(1/sqrt(k)) - atan(sqrt(k)) for the axis
ratio k of the map (0.29 deg at k = 0.99).  Prints the mean over the references, how many
leave more than 0.25 and 0.5 deg, and (``-v``) every reference's line.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import bench.meter_bench_calibrated as mbc  # noqa: E402
from app.core.meter import calibrated, load_profile  # noqa: E402
from sim_robot.gauge_scene import distort_point  # noqa: E402
from sim_robot.gauge_styles import TUNING_FAMILIES  # noqa: E402


def true_view(truth: dict) -> np.ndarray:
    """The dial-to-image map's linear part at the pivot (central differences)."""
    hm = np.array(truth["homography"])
    k, (w, h) = truth["lens_k"], truth["frame_size"]
    p = np.linalg.solve(hm, [*truth["pivot_xy"], 1.0])
    p = p[:2] / p[2]

    def f(q):
        v = hm @ [q[0], q[1], 1.0]
        return np.array(distort_point(v[0] / v[2], v[1] / v[2], k, w, h))
    e = 0.5
    return np.column_stack([(f(p + [e, 0]) - f(p - [e, 0])) / (2 * e),
                            (f(p + [0, e]) - f(p - [0, e])) / (2 * e)])


def view_deg(m: np.ndarray) -> float:
    """The largest angle error (deg) the linear map ``m`` makes about the pivot."""
    s = np.linalg.svd(m, compute_uv=False)
    k = s[1] / s[0]
    return math.degrees(math.atan(1.0 / math.sqrt(k)) - math.atan(math.sqrt(k)))


def references(seed: int, folder: Path) -> list[dict]:
    """The seed's reference frames written to ``folder`` and their truths (the frames the
    stream composes before its first lap)."""
    got = []
    compose = mbc.compose

    def kept(*a, **kw):
        img, truth = compose(*a, **kw)
        got.append(truth)
        return img, truth
    mbc.compose = kept
    try:
        next(mbc.cal_ref_stream(TUNING_FAMILIES, 0, seed, folder))
    finally:
        mbc.compose = compose
    return got[:-1]  # (the last one is the first lap's frame)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="11-40", help="first-last")
    ap.add_argument("-v", action="store_true", help="every reference's line")
    args = ap.parse_args()
    first, last = (int(s) for s in args.seeds.split("-"))
    left = []
    for seed in range(first, last + 1):
        with tempfile.TemporaryDirectory(prefix="meter-cal-ref-views-") as tmp:
            for truth in references(seed, Path(tmp)):
                prof = load_profile(Path(tmp) / f"{truth['style']}.json")
                calibrated._REFERENCES.clear()
                rect = calibrated._reference_geometry(prof.calibration, prof)[0]
                j = true_view(truth)
                left.append(view_deg(rect.a @ j))
                if args.v:
                    print(f"{seed} {truth['style']:7s} {truth['family']:9s} view "
                          f"{view_deg(j):.2f} left {left[-1]:.2f} deg; rim "
                          f"{'none' if rect.identity else f'{rect.axis_ratio:.4f}'} "
                          f"on {rect.support:.2f} of its rays", flush=True)
    print(f"{len(left)} references: view left mean {np.mean(left):.3f} deg, "
          f"> 0.25 deg {sum(x > 0.25 for x in left)}, > 0.5 deg {sum(x > 0.5 for x in left)}")


if __name__ == "__main__":
    main()
