"""A far match judged against its rival: the best other placement of the scan.

A long-range match (long_range.py) searches a window of up to ± 2 m round
the solved pose, and in a hall of regular walls a placement a wall spacing
along it can score as well as the right one: the matcher then returns
whichever scores a little higher, and the inlier share (0.25 or more) does
not tell them apart. The test here is Lowe's ratio test (D. Lowe,
"Distinctive image features from scale-invariant keypoints", IJCV 2004,
§7.1: a match is kept only when its nearest neighbour is clearly nearer than
the second nearest) on the correlative search's score (E. Olson,
"Real-time correlative scan matching", ICRA 2009):

1. **The score volume.** The scan's score (Σ of the coarse likelihood field
   at its points) at every (x, y, θ) of the search's coarse grid round the
   guess: the same grid as ``submap_match.search``'s first stage.
2. **The rival.** The volume's peaks (each at least as high as its 26
   neighbours, so that a point on the match's own shoulder is none) whose
   translation lies at least ``exclude_m`` from the match's, best first;
   each refined as the match is (the fine search within one coarse step,
   then ``submap_match.refine``) until one stays that far from the match.
3. **The ratio.** The match's mean fine-field value over the rival's
   (long_range.py keeps a judged match when it is at least
   ``rival_ratio``, 7.). A window without such a peak has no rival.

What it cannot tell: on edmonton-every2-reversed-x1.5 the scans of a dead
end that see a region's walls at inlier shares 0.25–0.3 score *lower* at
their true placement (mean value 0.07–0.2) than at the aliased one the
matcher found (0.2–0.23), and their right matches have rivals within a
ratio of 1.2 as well (docs/localisation.md).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy.ndimage import maximum_filter

from .submap_match import Submap, _grid_search, _thin, _values, refine


@njit(cache=True)
def _score_volume(src, gx, gy, gth, offs, dths, grid, lox, loy, res):
    """score[ix, iy, j]: Σ_i field(R(gth + dths[j]) src_i + (gx, gy) + (offs[ix], offs[iy]))."""
    h, w = grid.shape
    n, m = offs.shape[0], dths.shape[0]
    out = np.zeros((n, n, m))
    for j in range(m):
        c, s = math.cos(gth + dths[j]), math.sin(gth + dths[j])
        for i in range(src.shape[0]):
            bx = c * src[i, 0] - s * src[i, 1] + gx
            by = s * src[i, 0] + c * src[i, 1] + gy
            for ix in range(n):
                cx = min(max(int(math.floor((bx + offs[ix] - lox) / res)), 0), w - 1)
                for iy in range(n):
                    cy = min(max(int(math.floor((by + offs[iy] - loy) / res)), 0), h - 1)
                    out[ix, iy, j] += grid[cy, cx]
    return out


def rival(source: np.ndarray, sub: Submap, guess, window_xy_m: float,
          window_theta_rad: float, match_pose, exclude_m: float = 0.4, tries: int = 4):
    """The best placement of ``source`` in ``sub`` over guess ± the window
    whose translation lies at least ``exclude_m`` from ``match_pose``'s,
    refined; returns (pose, mean fine-field value of the points there), or
    (None, 0.0) when the window holds no such placement."""
    c = sub.cfg
    src = _thin(source, 120)
    f = sub.coarse
    n = int(round(window_xy_m / c.coarse_res_m))
    m = int(round(window_theta_rad / c.coarse_step_theta_rad))
    offs = np.arange(-n, n + 1) * c.coarse_res_m
    dths = np.arange(-m, m + 1) * c.coarse_step_theta_rad
    g = np.asarray(guess, float)
    vol = _score_volume(src, float(g[0]), float(g[1]), float(g[2]), offs, dths, f.grid,
                        float(f.lo[0]), float(f.lo[1]), float(f.res))
    # the volume's own peaks (each (x, y, θ) at least as high as its 26
    # neighbours): a point on the match's shoulder is none
    peak = vol >= maximum_filter(vol, size=3, mode="nearest")
    dx = g[0] + offs[:, None, None] - float(match_pose[0])
    dy = g[1] + offs[None, :, None] - float(match_pose[1])
    peak &= (np.hypot(dx, dy) >= exclude_m) & (vol > 0)
    cand = np.argwhere(peak)
    order = np.argsort(-vol[peak])[:tries]
    pts = _thin(source, c.max_points)
    for ix, iy, j in cand[order]:
        start = np.array([g[0] + offs[ix], g[1] + offs[iy], g[2] + dths[j]])
        pose, _ = _grid_search(src, sub.fine, start, c.coarse_res_m, c.res_m,
                               c.coarse_step_theta_rad, c.fine_step_theta_rad)
        pose, _ = refine(pts, sub, pose)
        if math.hypot(pose[0] - match_pose[0], pose[1] - match_pose[1]) >= exclude_m:
            return pose, float(np.mean(_values(pts, pose, sub.fine)))
    return None, 0.0


def match_value(source: np.ndarray, sub: Submap, pose) -> float:
    """The mean fine-field value of ``source``'s points at ``pose`` (the
    score the ratio compares)."""
    return float(np.mean(_values(_thin(source, sub.cfg.max_points), pose, sub.fine)))
