"""Diagnoses of the face-aware submap grid (face_grid.py) on the real logs.

    PYTHONPATH=$PWD python bench/face_grid_check.py points
    PYTHONPATH=$PWD python bench/face_grid_check.py plaincov --part logs --logs none \
        --variants edmonton-every2 --methods full-facegrid-only --draws 0,5,8

``points``: at the logs' reference poses, every 7th scan (edmonton, every
second edmonton scan, freiburg) against a grid of its 5 predecessors, plain
and layered (SubmapConfig.face_bins 12): the share of the scan's points on a
wall (plain value over 0.3) that lose it in their layer (value lower by over
0.3), the share of the grid's points seen from anywhere, the mean distance
from the reference pose of the grid fit searched from it (± 0.3 m, ± 2°), and
the fits' stated σ_xy.

``plaincov``: bench/localisation_bench.py with the rest of its arguments,
the layered grids' Olson covariance read on the plain grid (the layers'
maximum) instead of the layers: whether a change on the logs comes from the
covariance or from the fit.
"""

from __future__ import annotations

import runpy
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import app.core.localisation.submap_match as sm  # noqa: E402
from app.core.localisation.carmen import read_log  # noqa: E402
from app.core.localisation.match_covariance import olson_covariance  # noqa: E402
from app.core.localisation.slam import scan_points  # noqa: E402

CARMEN = ROOT.parent / "shared" / "carmen"


def points() -> None:
    for name, step in (("edmonton-corrected.log.gz", 1), ("edmonton-corrected.log.gz", 2),
                       ("freiburg-101-corrected.log.gz", 1)):
        log = read_log(CARMEN / name)
        pts = scan_points(log)[::step]
        ref = np.array([s.pose for s in log.scans])[::step]
        plain, lay = sm.SubmapConfig(), sm.SubmapConfig(face_bins=12)
        lost, on_wall, anywhere, rows = 0, 0, [], []
        for j in range(5, len(pts), 7):
            kf = [(ref[i], pts[i]) for i in range(j - 5, j)]
            a, b = sm.Submap(kf, plain), sm.Submap(kf, lay)
            src = sm._thin(pts[j], 400)
            va, vb = sm._values(src, ref[j], a.fine), sm._values(src, ref[j], b.fine)
            wall = va > 0.3
            lost += int(np.sum(wall & (vb < va - 0.3)))
            on_wall += int(wall.sum())
            anywhere.append(np.mean(~b.facing.any(axis=1)))
            fits = [sm.match_submap(pts[j], g, ref[j], 0.3, np.radians(2), 4) for g in (a, b)]
            rows.append([np.hypot(*(r.pose[:2] - ref[j][:2])) for r in fits]
                        + [np.sqrt(r.covariance[0, 0] + r.covariance[1, 1]) for r in fits])
        m = np.mean(rows, axis=0)
        print(f"{name} every {step}: wall points losing their wall {lost}/{on_wall} "
              f"({lost / on_wall:.3f}); grid points seen from anywhere {np.mean(anywhere):.3f}; "
              f"fit off the reference plain {m[0]:.3f}, layered {m[1]:.3f} m; "
              f"sigma_xy plain {m[2]:.3f}, layered {m[3]:.3f} m")


def _plain_covariance(source, sub, pose, half_steps=2, kind=None):
    c = sub.cfg
    return olson_covariance(sm._thin(source, 90), sub.fine, pose, c.res_m,
                            c.fine_step_theta_rad, half_steps)


def main() -> None:
    if len(sys.argv) < 2 or sys.argv[1] not in ("points", "plaincov"):
        sys.exit(__doc__)
    if sys.argv[1] == "points":
        points()
        return
    sm.covariance = _plain_covariance  # match_submap reads the module's name at call time
    sys.argv = [str(ROOT / "bench" / "localisation_bench.py")] + sys.argv[2:]
    runpy.run_path(sys.argv[0], run_name="__main__")


if __name__ == "__main__":
    main()
