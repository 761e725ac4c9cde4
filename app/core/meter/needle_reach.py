"""How far each end of the needle reaches along its axis (:func:`.needle.find_needle`,
step 3).

An end's reach is the outermost radius of a run of the polar response above a threshold
from the hub, gaps up to ``GAP`` bridged (glare across the needle) (:func:`_extent`).  The
end opposite the strongest one is also measured against its own strength at its root,
without bridging (:func:`_unbroken`): a thin tapered tip is fainter than a wide tail and
would fade under the tail's threshold.

The axis is the middle of the strongest direction's lobe, and when that end is a wide
tail (a paddle, a fin) about a pivot clicked a few pixels off, the lobe's middle lies a
few degrees off the needle's line; a hairline tip on the other side then leaves the
opposite ray as it goes out and seems to end halfway, shorter than the tail with the print
beyond it.  :func:`other_end` (the calibrated reader) also looks on the rays within the
lobe's half-width (at most ``SEARCH_DEG``) of the opposite one, and takes one of them for
that end only where the end reaches clearly farther there than the axis's end does: where
it would not become the tip, the exact opposite stays (a set-point pointer's disc, a
little off centre, is no tail).
"""

from __future__ import annotations

import numpy as np

from .needle_line import N_TH, R_IN
from .order_stats import percentile

__all__ = ["GAP", "ROOT_R", "other_end"]

GAP = 0.15  # gaps in the needle bridged when measuring its extent (glare), units of R
ROOT_R = 0.4  # an end's own strength is judged at its root, out to this radius (units of R)
ROOT_FLOOR = 0.25  # ... and is no less than this share of the needle's best ray (noise)
ROOT_GAP = 0.03  # such a faint end is measured unbroken (gaps up to this, units of R)
SEARCH_DEG = 3.0  # the other end looked for this far either side of the opposite ray
CLEARLY = 0.1  # ... and taken there when it reaches this much farther (units of R)


def _extent(ray: np.ndarray, rs: np.ndarray, thr: float, gap_px: float,
            late: float = 0.0) -> float:
    """Outermost radius reached by a run of ``ray > thr`` from the hub, bridging gaps:
    the first radius on must lie within ``gap_px + late`` of the first radius, and each
    next one within ``gap_px`` of the one before."""
    r_on = rs[ray > thr]
    if len(r_on) == 0 or r_on[0] - rs[0] > gap_px + late:
        return 0.0
    jump = (r_on[1:] - r_on[:-1] > gap_px).nonzero()[0]
    return float(r_on[jump[0]] if len(jump) else r_on[-1])


def _unbroken(ray: np.ndarray, rs: np.ndarray, R: float, s_best: float) -> tuple:
    """(reach, threshold) of one end of the needle measured without bridging gaps, against
    its own strength at its root (out to ``ROOT_R``, no less than ``ROOT_FLOOR`` of the best
    ray ``s_best``)."""
    root = ray[(rs >= R_IN * R) & (rs <= ROOT_R * R)]
    level = float(percentile(root, 75)) if len(root) else 0.0  # (np.percentile's)
    thr = 0.4 * min(s_best, max(level, ROOT_FLOOR * s_best))
    # (it may start as far out as a bridged one: behind the hub's cap)
    return _extent(ray, rs, thr, ROOT_GAP * R, (GAP - ROOT_GAP) * R), thr


def other_end(wide: np.ndarray, rs: np.ndarray, R: float, j: int, lobe: tuple[int, int],
              thr: float, s_best: float, ext_a: float, search: bool = True) -> tuple:
    """(ray, bridged reach, unbroken reach, the unbroken reach's threshold) of the end
    opposite the axis: on the opposite ray ``j``, or (``search``) on a ray within the axis
    lobe's half-width of it where the end reaches more than CLEARLY x R beyond ``ext_a``,
    the axis's end, and farther than on ``j``.  ``wide``: the widened polar response;
    ``lobe``: the axis lobe's first and last rays (unwrapped)."""
    gap = GAP * R
    ext_b = _extent(wide[j], rs, thr, gap)
    run_b, thr_b = _unbroken(wide[j], rs, R, s_best)
    if not search:
        return j, ext_b, run_b, thr_b
    half = min((lobe[1] - lobe[0]) // 2, int(round(SEARCH_DEG * N_TH / 360.0)))
    for dj in range(-half, half + 1):
        jj = (j + dj) % N_TH
        e_b = _extent(wide[jj], rs, thr, gap)
        r_b, t_b = _unbroken(wide[jj], rs, R, s_best)
        if max(e_b, r_b) > max(ext_b, run_b, ext_a + CLEARLY * R):
            j, ext_b, run_b, thr_b = jj, e_b, r_b, t_b
    return j, ext_b, run_b, thr_b
