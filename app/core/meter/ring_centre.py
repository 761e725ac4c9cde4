"""The centre of the ring of the scale's printed marks: a second estimate of the pivot.

:mod:`.angles` reads a dial against the profile's angles about a pivot that two estimates
must agree on.  One is the hub's circle (:mod:`.pointer`); this module gives the other,
which shares no step with it: a gauge's scale is concentric with its pivot, so a circle
(eq. 20's form, seed 000 section 3.2) fitted to the scale marks' outer or inner ends,
found column by column of the polar image, places the pivot too (:func:`ring_centre`).
The needle's region is hidden from that evidence (:func:`needle_only`); the same ring
says whether the hub may be the image of the dial's centre under perspective
(:func:`hub_is_perspective_centre`), before the perspective is removed about it.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .arc_fit import STEP, ring_rows
from .dial import FACE_RADIUS
from .geometry import fit_circle
from .pointer import CENTRE
from .scale import polar

__all__ = ["ring_centre", "needle_only", "hidden_float", "pass_images",
           "hub_is_perspective_centre", "CENTRES_AGREE_PX"]

NEEDLE_CORRIDOR_PX = 12.0  # half-width of a needle with its arrow head or counterweight
MAX_CENTRE_SHIFT_PX = 15.0  # the scale ring's centre this far from the hub is no estimate
CENTRES_AGREE_PX = 3.0  # hub and scale ring agree on the pivot within this
# a hub this near the rim's centre is allowed by every ring (its place under perspective
# lies nearer still); less than CENTRES_AGREE_PX by far more than the rounding of that test
NEAR_RIM_PX = CENTRES_AGREE_PX - 1e-9
CLAMPED_SHARE = 0.5  # a ring's ends this often on its first or last row say nothing
MIN_RING_ARC_DEG = 80.0  # a ring of strokes spanning less than this fixes no centre
_K5 = np.ones((5, 5), np.uint8)
# sin and cos of every polar column's angle (float64, as np.sin(np.radians(col * STEP)))
_SIN64 = np.sin(np.radians(np.arange(round(360.0 / STEP)) * STEP))
_COS64 = np.cos(np.radians(np.arange(round(360.0 / STEP)) * STEP))

def ring_centre(dark: np.ndarray, thr: float, centre, face_r: float,
                hidden_mask: np.ndarray | None, with_radius: bool = False,
                clamp_band: bool = False):
    """The centre of the ring of scale marks: a circle (eq. 20's form) fitted to the marks'
    outer ends (or their inner ends, whichever lie on a circle more closely), found column
    by column of the polar image about ``centre``.  Longer major ticks, numerals and colour
    zones are trimmed as outliers.  A gauge's scale is concentric with its pivot, so this
    estimates the pivot without any step of the hub's own circle.  Starts from ``centre``
    and refits once about its own result.  Returns ((x, y), rms px) or None.  ``dark`` and
    ``hidden_mask`` may come as float32 images already (the mask grown by
    :func:`hidden_float`), made once for several starts.  ``with_radius``: the ring's
    radius is returned too, ((x, y), rms px, radius px).  ``clamp_band``: the band's own
    rows are dropped, like the stroke rings', where most marks run past them (their ends
    are then the rows' and fit a circle about any start; the reader's angles path keeps
    them, which it was tuned with).
    """
    c = (float(centre[0]), float(centre[1]))
    best = None
    # the float images are the same for every start: the caller may pass them in once
    darkf = dark if dark.dtype == np.float32 else dark.astype(np.float32)
    if hidden_mask is None or hidden_mask.dtype == np.float32:
        hidden = hidden_mask
    else:
        hidden = hidden_float(hidden_mask)
    for _ in range(2):
        pol, rs = polar(darkf, c, 0.45 * face_r, 0.97 * face_r)
        rows_of = ring_rows(pol, thr)  # (found once per unwrap and threshold)
        b, rings = rows_of.b, rows_of.rings()
        if not rings:
            return None
        # the band most runs cross, and the rings of short radial strokes (ticks hanging
        # from or crossing a printed arc, which the band's rows may miss for numerals');
        # where the rings lie does not depend on the needle's columns (only their evidence
        # does, which is not used here)
        cands = [(b, max(0, rings[0][0] - 3), min(len(rs) - 1, rings[0][1] + 3))]
        short = rows_of.short()
        cands += [(short, lo, hi) for lo, hi in rows_of.tick_rows()]
        hid = None
        if hidden is not None:  # the needle's region, unwrapped over the rings' rows only
            r0, r1 = min(lo for _, lo, _ in cands), max(hi for _, _, hi in cands)
            pm, _ = polar(hidden, c, 0.45 * face_r, 0.97 * face_r, rows=slice(r0, r1 + 1))
            hid = pm > 0.05
        best = None
        for img, lo, hi in cands:
            sub = img[lo:hi + 1]
            if hid is not None:
                sub = sub & ~hid[lo - r0:hi + 1 - r0].any(axis=0)[None, :]
            cols = sub.any(axis=0).nonzero()[0]
            if len(cols) < 20:
                continue
            if img is not b and _arc_cover_deg(cols) < MIN_RING_ARC_DEG:
                continue  # a short arc of strokes (a zone's edge, a word) fixes no centre
            sin_t, cos_t = _SIN64[cols], _COS64[cols]
            sc = sub[:, cols]
            n_rows = hi + 1 - lo
            for edge in (n_rows - 1 - sc[::-1].argmax(axis=0),  # outer end
                         sc.argmax(axis=0)):  # inner end
                if (img is not b or clamp_band) and \
                        np.count_nonzero((edge == 0) | (edge == n_rows - 1)) / len(edge) \
                        > CLAMPED_SHARE:
                    continue  # the strokes run through the ring's rows: their ends are the
                    # rows' own, and a circle about the start fits them whatever the centre
                r_e = rs[lo + edge]
                fit = _trimmed_circle(c[0] + r_e * sin_t, c[1] - r_e * cos_t)
                if fit is not None and (best is None or fit[1] < best[1]):
                    best = fit
        if best is None:
            return None
        (m, nn), _, _ = best
        if math.hypot(m - centre[0], nn - centre[1]) > MAX_CENTRE_SHIFT_PX:
            return None
        c = (float(m), float(nn))
    return (c, best[1], best[2]) if with_radius else (c, best[1])


def _arc_cover_deg(cols: np.ndarray) -> float:
    """Degrees of the circle from the first to the last of the polar columns ``cols``
    (sorted) the short way round: 360 less the largest gap between them."""
    gaps = np.diff(np.concatenate([cols, [cols[0] + round(360.0 / STEP)]]))
    return 360.0 - float(gaps.max()) * STEP


def hidden_float(hidden_mask: np.ndarray) -> np.ndarray:
    """The needle's region grown by 2 px, as the float image :func:`ring_centre` unwraps."""
    return cv2.dilate(hidden_mask, _K5).astype(np.float32)


def pass_images(res: dict) -> tuple[np.ndarray, np.ndarray]:
    """(``res["dark"]`` as float32, ``hidden_float(needle_only(res["pmask"], res["line"]))``)
    of a pointer pass's result: the images the angles path, the pivot checks and the
    perspective check each unwrap about the hub.  Made once per result and read-only, so
    that :func:`.scale.polar` unwraps them once per centre (the same values as made
    afresh by each)."""
    dark, pmask, line = res["dark"], res["pmask"], res["line"]
    for d, p, ln, got in tuple(_PASS_IMAGES):
        if d is dark and p is pmask and ln is line:
            return got
    darkf, hidden = dark.astype(np.float32), hidden_float(needle_only(pmask, line))
    darkf.flags.writeable = hidden.flags.writeable = False
    _PASS_IMAGES.append((dark, pmask, line, (darkf, hidden)))
    if len(_PASS_IMAGES) > 3:
        del _PASS_IMAGES[0]
    return darkf, hidden


# the newest passes' float images (each entry holds the result's arrays, whose ids it keys on)
_PASS_IMAGES: list[tuple] = []


def _trimmed_circle(px: np.ndarray, py: np.ndarray):
    """((x, y), rms, radius) of a circle fitted to the points (px, py) (contiguous
    arrays) that lie on it, or None.

    Each round is :func:`.geometry.fit_circle` on the points kept, written out here on the
    coordinates' two arrays: the same sums in the same order (the same
    values), but one distance per point serves both the fit's rms (over the points kept)
    and the trimming (over all of them), and the rounds make a few numpy calls each
    instead of a dozen, as this runs some ten times per ring."""
    n_all = len(px)
    # the coordinates as the two rows of one array: each step below is one numpy call on
    # both, with each row's values and sums as on its own array (the kept points are taken
    # by compress, which keeps the rows C-ordered; pts[:, keep] gives a column-major copy,
    # whose rows numpy sums in another order, a few units in the last place apart)
    pts = np.empty((2, n_all))
    pts[0], pts[1] = px, py
    keep, n_keep = None, n_all
    for _ in range(4):
        if n_keep < 20:
            return None
        m, n, r, d = _circle_dist(pts if keep is None else pts.compress(keep, axis=1), pts)
        dk = d if keep is None else d[keep]
        rms = math.sqrt(float(np.add.reduce(dk * dk)) / n_keep)
        new = np.abs(d) < max(1.0, 2.0 * rms)
        if keep is None:
            if new.all():
                break
        elif new.tobytes() == keep.tobytes():  # (np.array_equal of two bool arrays alike)
            break
        keep, n_keep = new, int(np.count_nonzero(new))
    if n_keep < max(20, 0.4 * n_all):
        return None
    return (m, n), rms, r


def _circle_dist(sel: np.ndarray, pts: np.ndarray):
    """:func:`.geometry.fit_circle`'s algebraic circle (eq. 20) through the points ``sel``
    (2 x k: x row, y row), and the signed distance of every point of ``pts`` (2 x n) from
    it: (m, n, r, distances)."""
    k = sel.shape[1]
    o = np.add.reduce(sel, axis=1) / k  # (each row's sum as np.add.reduce of that row)
    ox, oy = float(o[0]), float(o[1])
    x, y = sel[0] - ox, sel[1] - oy
    z = x * x + y * y
    sxx, sxy, syy = float(x @ x), float(x @ y), float(y @ y)
    sxz, syz = 0.5 * float(x @ z), 0.5 * float(y @ z)
    det = sxx * syy - sxy * sxy
    if det <= 1e-12 * max(sxx * syy, 1e-300):  # collinear: fit_circle's own answer
        m, n, r, _ = fit_circle(sel.T.copy())
    else:
        m0 = (sxz * syy - syz * sxy) / det
        n0 = (syz * sxx - sxz * sxy) / det
        cz = float(np.add.reduce(z)) / k
        m, n = m0 + ox, n0 + oy
        r = math.sqrt(max(cz + m0 * m0 + n0 * n0, 0.0))
    # (each row less its centre coordinate, as pts - [[m], [n]] gives it)
    return float(m), float(n), float(r), np.hypot(pts[0] - m, pts[1] - n) - r


def needle_only(pmask: np.ndarray, line) -> np.ndarray:
    """The pointer's region near its axis: the region may have grown into a printed arc or
    ticks the needle touches, which must stay evidence, not be hidden with the needle."""
    nz = cv2.findNonZero(pmask)
    out = np.zeros_like(pmask)
    if nz is None:
        return out
    xs, ys = nz.reshape(-1, 2).T
    keep = line.distance(np.column_stack([xs, ys]).astype(float)) < NEEDLE_CORRIDOR_PX
    out[ys[keep], xs[keep]] = 1
    return out


def hub_is_perspective_centre(res: dict, rim_radius: float, hub=None,
                              every_ring: bool = False) -> bool:
    """Whether the scale ring lets the hub of ``res`` (an affine-rectified crop, the rim a
    circle of ``rim_radius`` about the crop's centre) be the image of the dial's centre, so
    that the perspective may be removed about it (:func:`.dial.rectify_projective`).

    Under perspective the images of concentric circles are ellipses whose centres lie off
    the image of their common centre p by an amount growing with the square of their
    radius (to first order): rim centre = p + k R^2, scale ring's centre = p + k rho^2.
    A hub off the rim's centre by perspective therefore drags the scale ring's centre
    along, to ``hub + (rim centre - hub) (rho / R)^2``; with the rim's centre as the pivot
    (no perspective to remove) the ring is centred there.  The hub is accepted when the
    ring's centre is nearer the first place than the second, or when the two lie within
    the fits' noise of each other (a hub near the rim's centre).  A
    ring centred elsewhere says the hub is not the pivot (a needle's counterweight, a
    logo): rectifying about it would make the ring concentric with it and leave no
    independent check of the pivot.  True when the ring is not found (nothing contradicts
    the hub).

    ``hub``: the point to test, when it is not the hub of ``res`` (e.g. a scale ring's
    centre proposed as the pivot).  ``every_ring``: the rings fitted from both starts (the
    point and the rim's centre) must each allow it, not only the one that fits a circle
    more closely.  Two rings of marks (the ticks' ends and a ring of numerals, say) may
    fit circles about two different centres equally well; the point is the dial's centre
    only if the perspective model places every ring of marks found where it lies."""
    hub = np.asarray(res["centre"] if hub is None else hub, float)
    rim = np.array([CENTRE, CENTRE])
    if float(np.hypot(*(hub - rim))) <= NEAR_RIM_PX:
        # wherever a ring lies, the place it would have under perspective lies between the
        # hub and the rim's centre, so within the fits' noise of the latter: every ring
        # allows the hub (:func:`_ring_allows`'s first test), and none need be fitted
        return True
    darkf, hidden = pass_images(res)
    fits = [ring_centre(darkf, res["otsu_t"], start, FACE_RADIUS, hidden, with_radius=True,
                        clamp_band=True)
            for start in (tuple(hub), tuple(rim))]
    fits = [f for f in fits if f is not None]
    if not fits:
        return True
    return all(_ring_allows(hub, rim, ring_c, rho, rim_radius)
               for ring_c, _, rho in (fits if every_ring else [min(fits, key=lambda f: f[1])]))


def _ring_allows(hub: np.ndarray, rim: np.ndarray, ring_c, rho: float,
                 rim_radius: float) -> bool:
    """Whether a ring of marks of radius ``rho`` centred at ``ring_c`` lets ``hub`` be the
    image of the dial's centre (:func:`hub_is_perspective_centre`)."""
    expected = hub + (rim - hub) * min(rho / rim_radius, 1.0) ** 2
    if float(np.hypot(*(expected - rim))) <= CENTRES_AGREE_PX:
        return True  # the two places lie within the fits' noise: the ring cannot tell
    miss = float(np.hypot(*(np.asarray(ring_c) - expected)))
    return miss <= float(np.hypot(*(np.asarray(ring_c) - rim)))
