"""The dial's concentric print as a witness of a reference frame's rim (issue 11, section 1,
a calibration with a reference frame).

A rim that not every ray has a step on may mix two edges (the face's edge on some rays,
the bezel's or a printed arc's on the others): its ellipse is then flatter than the dial's
view, by an axis ratio of about 0.96 on dials seen nearly head-on, and its correction
moves every reading of the point by up to half a percent of full scale.
:mod:`.rim_witness` replaces it where two other edges agree on another shape; where none
do, the whole dial decides.  Its face's edge, the bezel's edges, the printed arcs and the
ticks' ends are all circles about the pivot, so seen through the right shape (the map that
turns the view's ellipses back into circles) the dial unwrapped about the pivot has each of
them on one radius, and its profile along the radius (the median over the angles) has
its steps at their sharpest; through a wrong shape each circle is smeared over a band of
radii (:func:`focus`).  Under perspective the circles' images are centred off the pivot
by a shift growing as the square of their radius: the shift is fitted for every shape
(:func:`_best_shift`), so that a shape is not judged by a centre the view moved.

:func:`sharpest_rim` weighs the rim found, no correction (head-on) and every other rim
hypothesis of :mod:`.rim_witness` by that sharpness, where the rim is on less than
``CLEAN`` of its rays; a rim on more is kept (the sharpness is blunter than a clean rim's
fit: on the tuning seeds it prefers no correction over a right rim of 0.98 on a few
dials).  This is done once per reference file (:func:`.calibrated.prepare` does it before
the point's first frame).
"""

from __future__ import annotations

import logging
import math

import cv2
import numpy as np

from .oblique import Rectifier, _stretch
from .rim_witness import CLEAN, rim_hypotheses, shape_gap

__all__ = ["focus", "sharpest_rim"]

log = logging.getLogger(__name__)

R_LO, R_HI = 0.6, 1.8  # the ring unwrapped, in scale radii: ticks, arcs, the face's edge, bezel
R_STEP = 0.5  # px along the radius
N_ANGLES = 360
SHIFT_RADIUS = 1.3  # the centre's shift is fitted at this many scale radii (about the rim)
SHIFT_STEPS = (2.0, 1.0, 0.5)  # px: the shift's search, coarse to fine
SAME_SHAPE = 0.002  # hypotheses this close in shape (:func:`.rim_witness.shape_gap`) are one


def _unit(m: np.ndarray) -> np.ndarray:
    return m / math.sqrt(abs(np.linalg.det(m)))


def _grid(radius: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The unwrapped ring's offsets from the pivot on the dial (x, y: radii x angles) and
    each radius's share of the centre's shift (radii x 1): the same for every view tried."""
    rs = np.arange(R_LO * radius, R_HI * radius, R_STEP)
    th = np.linspace(0.0, 2.0 * np.pi, N_ANGLES, endpoint=False)
    dx = np.sin(th)[None, :] * rs[:, None]
    dy = -np.cos(th)[None, :] * rs[:, None]
    return dx, dy, (rs / (SHIFT_RADIUS * radius))[:, None] ** 2


def _view_maps(pivot, shape: np.ndarray, grid) -> tuple[np.ndarray, np.ndarray]:
    """The unwrapped ring's image points through ``shape`` before the centre's shift (x, y:
    radii x angles, float64): made once per view, the shifts added by :func:`_focus_many`."""
    px, py = float(pivot[0]), float(pivot[1])
    inv = np.linalg.inv(_unit(shape))
    dx, dy, _ = grid
    return px + inv[0, 0] * dx + inv[0, 1] * dy, py + inv[1, 0] * dx + inv[1, 1] * dy


def _focus_many(gray: np.ndarray, maps, k: np.ndarray, shifts) -> list[float]:
    """:func:`focus` for each of ``shifts`` through one view (``maps``: :func:`_view_maps`),
    the unwrapped rings stacked into one remap.  The median profile is taken from a sort
    along the angles (the mean of its two middle values, as ``np.median``'s): the same
    numbers, several times faster than a partition."""
    bx, by = maps
    n_r = bx.shape[0]
    mx = np.empty((len(shifts) * n_r, bx.shape[1]), np.float32)
    my = np.empty_like(mx)
    for i, s in enumerate(shifts):  # (summed in float64, rounded once to float32)
        np.add(bx, s[0] * k, out=mx[i * n_r:(i + 1) * n_r], casting="unsafe")
        np.add(by, s[1] * k, out=my[i * n_r:(i + 1) * n_r], casting="unsafe")
    v = cv2.remap(gray, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    v.sort(axis=1)
    n = v.shape[1]  # (the needle and the numerals are a few angles each)
    prof = (v[:, (n - 1) // 2] + v[:, n // 2]) / np.float32(2.0)
    out = []
    for p in prof.reshape(len(shifts), -1):
        step = p[2:] - p[:-2]
        out.append(float(step @ step))
    return out


def focus(gray: np.ndarray, pivot, radius: float, shape: np.ndarray, shift,
          grid=None) -> float:
    """How sharp the dial's circles are when ``gray`` (float32) is unwrapped about ``pivot``
    through ``shape`` (a linear map of image vectors onto the dial), the circle of radius r
    centred off the pivot by ``shift`` (r / (``SHIFT_RADIUS`` radius))^2: the sum of the
    squared steps of the median profile along the radius.  ``grid``: :func:`_grid`'s
    answer for ``radius``, when made once for several views."""
    grid = _grid(radius) if grid is None else grid
    return _focus_many(gray, _view_maps(pivot, shape, grid), grid[2], [shift])[0]


def _best_shift(gray: np.ndarray, pivot, radius: float, shape: np.ndarray, start) -> float:
    """:func:`focus` at its best over the centre's shift, searched from ``start`` on a
    3 x 3 grid at each of ``SHIFT_STEPS`` (a step's 8 shifts about the best so far are
    unwrapped together, then taken in turn)."""
    grid = _grid(radius)
    maps = _view_maps(pivot, shape, grid)
    at = (float(start[0]), float(start[1]))
    best = _focus_many(gray, maps, grid[2], [start])[0]
    for step in SHIFT_STEPS:
        cx, cy = at
        tried = [(cx + dx, cy + dy) for dx in (-step, 0.0, step) for dy in (-step, 0.0, step)
                 if dx or dy]
        for s, score in zip(tried, _focus_many(gray, maps, grid[2], tried), strict=True):
            if score > best:
                best, at = score, s
    return best


def _shift_of(ell, pivot, radius: float) -> tuple[float, float]:
    """The centre's shift at ``SHIFT_RADIUS`` scale radii that an ellipse's centre says."""
    (ex, ey), (w, h), _ = ell
    k = (SHIFT_RADIUS * radius / max(0.25 * (w + h), 1e-9)) ** 2
    return (ex - float(pivot[0])) * k, (ey - float(pivot[1])) * k


def sharpest_rim(gray: np.ndarray, pivot, clicked, radius: float, rect: Rectifier) -> Rectifier:
    """``rect`` (the rim found on ``gray`` about the ``clicked`` pivot), or, where it is on
    less than ``CLEAN`` of its rays, whichever of it, no correction and the other rim
    hypotheses makes the dial's circles sharpest about ``pivot`` (the refined pivot):
    see the module's docstring."""
    if rect.identity or rect.support >= CLEAN:
        return rect
    g = gray.astype(np.float32)
    cands: list[tuple[Rectifier | None, np.ndarray, tuple]] = [
        (rect, rect.a, _shift_of(rect.ellipse, pivot, radius)),
        (None, np.eye(2), (0.0, 0.0))]
    for h in rim_hypotheses(gray, clicked, radius):
        if any(c[0] is not None and c[0].ellipse is not None
               and shape_gap(h.ellipse, c[0].ellipse) < SAME_SHAPE for c in cands):
            continue
        (_, _), (w, hh), _ = h.ellipse
        ratio = min(w, hh) / max(w, hh)
        cands.append((Rectifier(_stretch(h.ellipse), h.ellipse, ratio, h.share),
                      _stretch(h.ellipse), _shift_of(h.ellipse, pivot, radius)))
    scores = [_best_shift(g, pivot, radius, a, s) for _, a, s in cands]
    k = int(np.argmax(scores))
    if k == 0:
        return rect
    got = cands[k][0]
    log.debug("the rim (axis ratio %.3f, %.2f of its rays) blurs the dial's circles: %s taken",
              rect.axis_ratio, rect.support,
              "no correction" if got is None else f"another edge's ({got.axis_ratio:.3f})")
    if got is None:
        out = Rectifier(None, None, 1.0)
        out.rim_seen = True
        return out
    return got
