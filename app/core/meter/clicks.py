"""The operator's clicks refined on the image itself (calibrated inspection points).

A person clicks the needle's pivot and the scale's two end marks to a few pixels.  On a
scale ring of 75 px radius, 3 px is more than 2 deg of angle, which on a 120 deg scale is
nearly 2 % of full scale: too much to use as it is.  Each click is therefore moved onto what
it points at, within a small radius, and kept as it is when the image does not show it
clearly:

* **The hub.**  Rays from the clicked pivot; on each, the two strongest steps of grey
  within ``0.3 R`` (R the scale ring's radius).  The circle most rays agree with (RANSAC
  over triples, Kasa's algebraic fit x^2 + y^2 + D x + E y + F = 0 solved linearly) leaves
  out the rays along the needle or through a highlight; an ellipse through its inliers
  (``cv2.fitEllipse``, refitted on its own inliers: a tilted dial's hub) gives the centre.
* **An end mark.**  The ring of the tick marks around the click (radii +-8 % of R, angles
  +-(``MAX_SHIFT_PX`` + 3) px) is unwrapped about the pivot; a morphological top-hat along
  the arc (dark or light, whichever is stronger; wider than the widest tick), which
  removes the scale's arc line and a
  colour band and keeps the ticks, averaged over the radii, is a profile of the ticks by
  angle.  The end mark is the outermost of the ticks with at least half the strongest
  one's mass across the arc: beyond the end of the scale there are no ticks of the scale
  (and none as strong may show beyond it, out to the whole window).  Its angle is the
  centroid of its run above half its height (a wide tick has a flat top); an end mark
  drawn as a hollow ring shows two such runs, its sides, with its hole between them under
  its cap, and its middle lies between them (:func:`_ring_partner`; a "0" printed just
  beyond the end tick is not one).  Where the
  needle lies over the window, outward of the tick found, the end mark may be under it:
  the click is kept.  Both end marks are major ticks of one print: one refined onto a tick
  much fainter than the other's is kept as clicked (:func:`matched_ends`).

A refinement that moves a click by more than ``MAX_SHIFT_PX`` is not trusted (but a hub
whose rim surrounds the click, off its centre by less than ``HUB_INSIDE`` of its radius,
is: the person clicked on that hub): the click is kept, and its uncertainty
(``CLICK_SIGMA_PX``) rather than a refined one (``FIT_SIGMA_PX``) goes into the reading's
confidence (:func:`fraction_sigma`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

__all__ = [
    "CLICK_SIGMA_PX",
    "FIT_SIGMA_PX",
    "MAX_SHIFT_PX",
    "Refined",
    "fraction_sigma",
    "matched_ends",
    "refine_end_mark",
    "refine_pivot",
    "tick_ends",
]

MAX_SHIFT_PX = 5.0  # a click is off by a few pixels; a refinement moving it farther is wrong
CLICK_SIGMA_PX = 1.8  # a click's error (about +-3 px, uniform) across its direction, 1 sigma
FIT_SIGMA_PX = 0.5  # a refined point's
N_HUB_RAYS = 48
HUB_TRIALS = 80
HUB_SHARE = 0.55  # of the rays must find the hub's rim
HUB_MIN = 0.06  # the smallest hub, in units of R (a highlight on the hub is smaller)
HUB_INSIDE = 0.8  # a hub whose rim surrounds the click this well may move it farther
MARK_BAND = 0.08  # radii of the tick ring around the clicked end mark, in units of R
MIN_TICK_CONTRAST = 8.0  # grey levels of a tick over the face
NEEDLE_HEAD = 0.05  # room for a needle's head beside its measured width, in units of R
TICK_MAX_PX = 12.0  # the widest tick (a wedge at its wide end) across the arc
TICK_SHARE = 0.5  # a tick of this share of the strongest one's mass may be the end mark
RING_SIDE = 0.6  # a ring's other side has this share of the outer side's height
RING_HOLE = 0.3  # a ring's hole: below this share of its sides' response
RING_CAP = 0.5  # a ring's cap across the hole: at least this share
END_MATCH = 0.35  # an end mark's tick has at least this share of the other end's contrast


@dataclass(frozen=True)
class Refined:
    """A refined click: ``xy`` (the click itself when ``ok`` is False), how far it moved,
    its uncertainty in px, and why it was not refined."""

    xy: tuple[float, float]
    ok: bool
    moved_px: float = 0.0
    sigma_px: float = CLICK_SIGMA_PX
    why: str = ""
    contrast: float = 0.0  # an end mark's tick: its height over the face, in grey levels
    ring_px: float = 0.0  # an end mark drawn as a ring: the distance between its sides
    side_hidden: bool = False  # the needle lies where a ring's inner side would be
    under_needle: bool = False  # an end mark placed on the needle's tip line (hidden_mark)
    width_px: float = 0.0  # an end mark's tick: its width across the arc at half height


def _kept(xy, why: str) -> Refined:
    return Refined((float(xy[0]), float(xy[1])), False, 0.0, CLICK_SIGMA_PX, why)


def refine_pivot(gray: np.ndarray, pivot, radius: float) -> Refined:
    """The hub's centre near the clicked ``pivot`` (grey image, scale ring ``radius`` px)."""
    px, py = float(pivot[0]), float(pivot[1])
    r_hi = max(6.0, 0.3 * radius)
    rs = np.arange(1.0, r_hi, 0.5, dtype=np.float32)
    th = np.linspace(0, 2 * np.pi, N_HUB_RAYS, endpoint=False).astype(np.float32)
    sx, sy = np.sin(th)[:, None], -np.cos(th)[:, None]
    mx = (px + sx * rs[None, :]).astype(np.float32)
    my = (py + sy * rs[None, :]).astype(np.float32)
    hgt, wid = gray.shape[:2]
    if not (r_hi < px < wid - r_hi and r_hi < py < hgt - r_hi):
        return _kept(pivot, "hub near the image's edge")
    v = cv2.remap(gray, mx, my, cv2.INTER_LINEAR).astype(np.float32)
    v = cv2.GaussianBlur(v, (3, 1), 0)
    d = np.abs(v[:, 2:] - v[:, :-2])
    # the two strongest steps of each ray (not at its first samples: the click may sit on
    # an edge) are its candidates for the hub's rim
    mid = d[:, 1:-1]
    is_max = (mid >= d[:, :-2]) & (mid > d[:, 2:]) & (mid > MIN_TICK_CONTRAST)
    is_max[:, :1] = False
    cand = np.argsort(np.where(is_max, -mid, 0.0), axis=1)[:, :2] + 1
    rows = np.repeat(np.arange(N_HUB_RAYS), 2)
    kc = cand.ravel()
    keep = is_max[rows, kc - 1]
    rows, kc = rows[keep], kc[keep]
    if len(np.unique(rows)) < N_HUB_RAYS // 2:
        return _kept(pivot, "no clear hub")
    y0, y1, y2 = d[rows, kc - 1], d[rows, kc], d[rows, kc + 1]
    den = y0 - 2 * y1 + y2
    off = np.clip(np.where(np.abs(den) > 1e-6, 0.5 * (y0 - y2) / np.where(den == 0, 1, den), 0),
                  -0.5, 0.5)
    r = rs[0] + 0.5 * (kc + 1 + off)
    x = (r * sx[rows, 0]).astype(np.float64)
    y = (r * sy[rows, 0]).astype(np.float64)
    fit = _circle_consensus(x, y, rows, tol=1.5)
    if fit is None:
        return _kept(pivot, "no round hub")
    cx, cy, rad, inl = fit
    # a highlight on a domed hub is a light disc inside its rim, off its centre: a circle
    # that most rays also find outside the first, enclosing it, is the hub's rim
    out = np.hypot(x - cx, y - cy) > rad + 1.5
    rim = _circle_consensus(x[out], y[out], rows[out], tol=1.5) if out.sum() >= 6 else None
    if rim is not None and math.hypot(rim[0] - cx, rim[1] - cy) + rad < rim[2] \
            and len(np.unique(rows[out][rim[3]])) >= HUB_SHARE * N_HUB_RAYS:
        cx, cy, rad = rim[:3]
        inl = np.abs(np.hypot(x - cx, y - cy) - rad) < 1.5
    # a tilted dial shows its hub as an ellipse: the circle's inliers give it, and its
    # centre is the pivot's
    for _ in range(2):
        if inl.sum() < 6:
            return _kept(pivot, "no round hub")
        ell = cv2.fitEllipse(np.column_stack([x[inl], y[inl]]).astype(np.float32))
        res = _ellipse_residual(x, y, ell)
        inl = res < 0.75
    (cx, cy), (ew, eh), _ = ell
    rad = 0.25 * (ew + eh)
    if min(ew, eh) < 0.6 * max(ew, eh):
        return _kept(pivot, "no round hub")
    moved = math.hypot(cx, cy)
    if len(np.unique(rows[inl])) < HUB_SHARE * N_HUB_RAYS \
            or not max(2.5, HUB_MIN * radius) < rad < r_hi - 1.0:
        return _kept(pivot, "no round hub")
    # the hub's rim must surround the fitted centre from all sides, not be one arc of it
    ang = np.arctan2(x[inl] - cx, -(y[inl] - cy))
    if np.bincount(((ang + np.pi) // (np.pi / 2)).astype(int) % 4, minlength=4).min() < 3:
        return _kept(pivot, "hub seen on one side only")
    if moved > max(MAX_SHIFT_PX, HUB_INSIDE * rad):  # a click on the hub lies inside it
        return _kept(pivot, f"hub {moved:.1f} px from the click")
    rms = float(np.sqrt(np.mean(res[inl] ** 2)))
    return Refined((px + cx, py + cy), True, moved, max(FIT_SIGMA_PX, rms))


def _ellipse_residual(x, y, ell) -> np.ndarray:
    """Approximate distance (px) of points from an ellipse in cv2 form."""
    (cx, cy), (w, h), ang = ell
    t = math.radians(ang)
    dx, dy = x - cx, y - cy
    xr = dx * math.cos(t) + dy * math.sin(t)
    yr = -dx * math.sin(t) + dy * math.cos(t)
    return np.abs(np.hypot(xr / max(w / 2, 1e-6), yr / max(h / 2, 1e-6)) - 1.0) * (w + h) / 4


def _circle(x, y) -> tuple[float, float, float] | None:
    """Kasa's algebraic circle through the points: x^2 + y^2 + D x + E y + F = 0."""
    a = np.column_stack([x, y, np.ones_like(x)])
    sol, *_ = np.linalg.lstsq(a, -(x * x + y * y), rcond=None)
    cx, cy = -sol[0] / 2, -sol[1] / 2
    r2 = cx * cx + cy * cy - sol[2]
    return (float(cx), float(cy), math.sqrt(r2)) if r2 > 0 else None


def _circle_consensus(x, y, ray, tol: float = 0.75):
    """The circle most rays agree with (RANSAC over triples of points, deterministic; a ray
    counts once), refit on its inliers: (cx, cy, r, inlier mask) or None.  A highlight
    inside the hub or the needle leaving it gives other steps on some rays; they are left
    out, not averaged in.  All trials at once: the circle through three points in closed
    form (the circumcentre)."""
    rng = np.random.default_rng(0)
    tri = rng.integers(0, len(x), size=(HUB_TRIALS, 3))
    ok = (ray[tri[:, 0]] != ray[tri[:, 1]]) & (ray[tri[:, 1]] != ray[tri[:, 2]]) \
        & (ray[tri[:, 0]] != ray[tri[:, 2]])
    tri = tri[ok]
    ax, ay = x[tri[:, 0]], y[tri[:, 0]]
    bx, by = x[tri[:, 1]], y[tri[:, 1]]
    qx, qy = x[tri[:, 2]], y[tri[:, 2]]
    d = 2.0 * (ax * (by - qy) + bx * (qy - ay) + qx * (ay - by))
    good = np.abs(d) > 1e-6
    if not good.any():
        return None
    d = np.where(good, d, 1.0)
    a2, b2, q2 = ax * ax + ay * ay, bx * bx + by * by, qx * qx + qy * qy
    ux = (a2 * (by - qy) + b2 * (qy - ay) + q2 * (ay - by)) / d
    uy = (a2 * (qx - bx) + b2 * (ax - qx) + q2 * (bx - ax)) / d
    rr = np.hypot(ax - ux, ay - uy)
    inl = np.abs(np.hypot(x[None, :] - ux[:, None], y[None, :] - uy[:, None])
                 - rr[:, None]) < tol
    inl &= good[:, None]
    rays = np.zeros((len(tri), N_HUB_RAYS), bool)
    t_i, p_i = np.nonzero(inl)
    rays[t_i, ray[p_i]] = True
    counts = rays.sum(axis=1)
    best = int(np.argmax(counts))
    if counts[best] < 5:
        return None
    c = _circle(x[inl[best]], y[inl[best]])
    if c is None:
        return None
    return (*c, np.abs(np.hypot(x - c[0], y - c[1]) - c[2]) < tol)


def _run(prof: np.ndarray, i: int) -> tuple[int, int]:
    """The run of samples around peak ``i`` above half its height (inclusive ends)."""
    half = 0.5 * prof[i]
    lo = i
    while lo > 0 and prof[lo - 1] > half:
        lo -= 1
    hi = i
    while hi < len(prof) - 1 and prof[hi + 1] > half:
        hi += 1
    return lo, hi


def _mass(prof: np.ndarray, i: int) -> float:
    """Sum of the profile over the run around peak ``i`` above half its height."""
    lo, hi = _run(prof, i)
    return float(prof[lo:hi + 1].sum())


def refine_end_mark(gray: np.ndarray, pivot, mark, outward: int, needle=(),
                    ring_px: float = 0.0) -> Refined:
    """The end mark's tick near the clicked ``mark``.  ``outward`` is +1 when the side off
    the scale at this mark is clockwise (the maximum of a clockwise scale), -1 otherwise.
    ``needle``: (image angle in degrees, reach in px, half-width in px) of each end of the
    needle; a tick the needle may hide is not looked for (the click is kept).  ``ring_px``:
    the other end mark is a ring with its sides this far apart; where the needle hides this
    mark's inner side, its middle is taken that far inside its outer side."""
    px, py = float(pivot[0]), float(pivot[1])
    mx0, my0 = float(mark[0]), float(mark[1])
    rm = math.hypot(mx0 - px, my0 - py)
    if rm < 12.0:
        return _kept(mark, "end mark too near the pivot")
    a0 = math.atan2(mx0 - px, -(my0 - py))
    step = 0.25 / rm  # radians per sample: a quarter pixel along the arc
    half = int(math.ceil((MAX_SHIFT_PX + TICK_MAX_PX + 2.0) / 0.25))  # room for the top-hat
    near = int(math.ceil((MAX_SHIFT_PX + 2.0) / 0.25))  # where the end mark is looked for
    ang = a0 + step * np.arange(-half, half + 1, dtype=np.float64)
    band = max(2.0, MARK_BAND * rm)
    rs = np.linspace(rm - band, rm + band, max(5, int(2 * band)))
    mx = (px + np.sin(ang)[None, :] * rs[:, None]).astype(np.float32)
    my = (py - np.cos(ang)[None, :] * rs[:, None]).astype(np.float32)
    hgt, wid = gray.shape[:2]
    if mx.min() < 0 or my.min() < 0 or mx.max() > wid - 1 or my.max() > hgt - 1:
        return _kept(mark, "end mark near the image's edge")
    v = cv2.remap(gray, mx, my, cv2.INTER_LINEAR).astype(np.float32)
    # ticks across the arc, dark or light: a closing (opening) along the arc wider than a
    # tick removes them and keeps the arc line, a colour band and the face's shading
    ker = np.ones((1, int(round(TICK_MAX_PX / 0.25)) | 1), np.uint8)
    hats = [cv2.morphologyEx(v, cv2.MORPH_CLOSE, ker) - v,
            v - cv2.morphologyEx(v, cv2.MORPH_OPEN, ker)]
    hat = max(hats, key=lambda q: float(q.mean(axis=0).max()))
    prof = hat.mean(axis=0)
    prof = cv2.GaussianBlur(prof[None, :].astype(np.float32), (5, 1), 0)[0]
    # the needle's samples (and 2 px beside it) hide what lies under them
    hidden = np.zeros(len(ang), bool)
    for deg, reach, hw in needle:
        if reach < rm - band:
            continue
        d = (ang - math.radians(deg) + np.pi) % (2 * np.pi) - np.pi
        hidden |= np.abs(d) * rm <= hw + 2.0 + NEEDLE_HEAD * rm  # a lance's head is wider
    seen = ~hidden & (np.abs(np.arange(len(prof)) - half) <= near)
    top = float(prof[seen].max()) if seen.any() else 0.0
    if top < MIN_TICK_CONTRAST * 0.5:
        return _kept(mark, "no clear tick at the end mark")
    # the outermost of the ticks with half the strongest one's mass across the arc
    peak = (prof[1:-1] >= prof[:-2]) & (prof[1:-1] > prof[2:]) & (prof[1:-1] >= 0.3 * top)
    peak &= ~hidden[1:-1] & (np.abs(np.arange(1, len(prof) - 1) - half) <= near)
    idx = np.flatnonzero(peak) + 1
    if len(idx) == 0:
        return _kept(mark, "no clear tick at the end mark")
    mass = np.array([_mass(prof, i) for i in idx])
    idx = idx[mass >= TICK_SHARE * mass.max()]
    k = int(idx[-1] if outward > 0 else idx[0])  # the outermost strong tick
    beyond = hidden[k:half + near + 1] if outward > 0 else hidden[half - near:k + 1]
    if beyond.any():  # the end mark may be under the needle
        return _kept(mark, "the needle covers the end mark")
    # the end of the scale: no tick as strong beyond it, out to the whole window (a click
    # far inside the scale would otherwise be moved onto the tick next to it)
    clear = np.where(hidden, 0.0, prof)  # (where the needle lies, it was looked at above)
    out = clear[k + 1:] if outward > 0 else clear[:k][::-1]
    gap = np.flatnonzero(out < 0.3 * prof[k])  # past the found tick's own flank
    if len(gap) and (out[gap[0]:] >= 0.5 * prof[k]).any():
        return _kept(mark, "a tick beyond the one found: not the scale's end")
    # the tick's middle: the centroid of its run above half height above that level (a
    # wide tick's flat top has no single highest sample)
    centre = _centroid(prof, k)
    j = _ring_partner(hat, prof, k, -outward, hidden)
    ring = 0.0
    inner = hidden[k - near:k] if outward > 0 else hidden[k + 1:k + near + 1]
    if j is not None:  # a hollow ring: its middle, between its two sides
        ring = abs(_centroid(prof, j) - centre) * 0.25
        centre = 0.5 * (centre + _centroid(prof, j))
    elif ring_px > 0 and inner.any():  # a ring like the other end's, its inner side hidden
        centre -= outward * 0.5 * ring_px / 0.25
    a = a0 + step * (centre - half)
    shift = rm * abs(a - a0)
    if shift > MAX_SHIFT_PX:
        return _kept(mark, f"tick {shift:.1f} px from the click")
    run = _run(prof, k)
    return Refined((px + rm * math.sin(a), py - rm * math.cos(a)), True, shift, FIT_SIGMA_PX,
                   contrast=float(prof[k]), ring_px=ring, side_hidden=bool(inner.any()),
                   width_px=0.0 if j is not None else (run[1] - run[0]) * 0.25)


def _centroid(prof: np.ndarray, k: int) -> float:
    """The centroid of the run around peak ``k`` above half its height, above that level."""
    lo, hi = _run(prof, k)
    w = prof[lo:hi + 1] - 0.5 * prof[k]
    return float((np.arange(lo, hi + 1) * w).sum() / max(float(w.sum()), 1e-9))


def _ring_partner(hat: np.ndarray, prof: np.ndarray, k: int, inward: int,
                  hidden: np.ndarray) -> int | None:
    """The other side of a hollow ring whose outer side is the peak ``k``, or None.

    An end mark drawn as a ring (a hollow circle) shows two peaks across the arc, its two
    sides, and the outermost one alone is a ring's radius off its middle.  The two sides
    are a peak inward within ``TICK_MAX_PX`` of about the same height, and between them the
    ring's hole: at the lowest column between them, two radii that both sides cover are
    empty while another (the ring's cap) is not.  Two separate ticks have no cap
    across the gap; two ticks blurred together have no empty hole.  A strong tick just
    inside it makes it a numeral ("0") beside the end tick, not a ring."""
    n = len(prof)
    stop = k + inward * int(TICK_MAX_PX / 0.25)
    lo, hi = (k + 1, min(n - 1, stop)) if inward > 0 else (max(0, stop), k - 1)
    if hi - lo < 4:
        return None
    seg = np.where(hidden[lo:hi + 1], 0.0, prof[lo:hi + 1])
    cand = [i for i in range(1, len(seg) - 1)
            if seg[i] >= seg[i - 1] and seg[i] > seg[i + 1] and seg[i] >= RING_SIDE * prof[k]]
    if not cand:
        return None
    j = lo + (cand[0] if inward > 0 else cand[-1])  # the nearest such peak
    run = _run(prof, k)
    if run[0] <= j <= run[1]:  # one run: its centroid is the mark's middle already
        return None
    a, b = sorted((j, k))
    c = a + int(np.argmin(prof[a:b + 1]))
    if c in (a, b) or hidden[a:b + 1].any():
        return None
    side_j, side_k = hat[:, j], hat[:, k]
    both = (side_j > 0.5 * side_j.max()) & (side_k > 0.5 * side_k.max())
    level = min(float(side_j.max()), float(side_k.max()))
    if both.sum() < 2 or level <= 0:
        return None
    col = hat[:, c]
    empty = both & (col < RING_HOLE * level)
    hole = bool((empty[1:] & empty[:-1]).any())  # two radii at least
    cap = bool((~empty & (col >= RING_CAP * level)).any())
    if not (hole and cap):
        return None
    # a tick just inside it is the end mark, and the ring a numeral ("0") beside it
    width = abs(j - k)
    j_lo, j_hi = _run(prof, j)  # beyond its inner side's own flank
    near_in = prof[j_hi + 1:j + int(1.5 * width)] if inward > 0 \
        else prof[max(0, j - int(1.5 * width)):j_lo]
    if len(near_in) and float(near_in.max()) >= RING_SIDE * float(prof[k]):
        return None
    return j


def tick_ends(gray: np.ndarray, pivot, mark) -> tuple[float, float] | None:
    """Inner and outer ends (px from ``pivot``) of the tick through the refined end mark
    ``mark``, or None when they are not clear.  A tick is radial: its image is on the line
    from the pivot through the mark, whatever the dial's tilt.  The ring around the mark
    (radii 0.75 - 1.25 x the mark's, along the arc +-(``TICK_MAX_PX`` + 4) px) is unwrapped
    about the pivot and top-hatted along the arc as in :func:`refine_end_mark` (the arc
    line, which ends at the end mark, and a colour band drop out; the ticks stay); the
    tick is the run of its response along the ray above half its height around the mark,
    each end placed to a fraction of a pixel at the half height.  Both end marks are major
    ticks of one print: their ends lie on circles about the pivot on the dial (used by
    :mod:`.calibrated` to test the dial's tilt)."""
    px, py = float(pivot[0]), float(pivot[1])
    rm = math.hypot(float(mark[0]) - px, float(mark[1]) - py)
    if rm < 12.0:
        return None
    a0 = math.atan2(float(mark[0]) - px, -(float(mark[1]) - py))
    half = int(math.ceil((TICK_MAX_PX + 4.0) / 0.25))
    ang = a0 + (0.25 / rm) * np.arange(-half, half + 1, dtype=np.float64)
    rs = np.arange(0.75 * rm, 1.25 * rm, 0.25, dtype=np.float64)
    mx = (px + np.sin(ang)[None, :] * rs[:, None]).astype(np.float32)
    my = (py - np.cos(ang)[None, :] * rs[:, None]).astype(np.float32)
    hgt, wid = gray.shape[:2]
    if mx.min() < 0 or my.min() < 0 or mx.max() > wid - 1 or my.max() > hgt - 1:
        return None
    v = cv2.remap(gray, mx, my, cv2.INTER_LINEAR).astype(np.float32)
    ker = np.ones((1, int(round(TICK_MAX_PX / 0.25)) | 1), np.uint8)
    mid = slice(half - 2, half + 3)  # the tick's middle, +-0.5 px
    hats = [(cv2.morphologyEx(v, cv2.MORPH_CLOSE, ker) - v)[:, mid].mean(axis=1),
            (v - cv2.morphologyEx(v, cv2.MORPH_OPEN, ker))[:, mid].mean(axis=1)]
    k0 = int(np.argmin(np.abs(rs - rm)))
    win = slice(max(k0 - 12, 0), k0 + 13)  # the click is on the tick, to about 3 px
    prof = max(hats, key=lambda q: float(q[win].max()))
    k = win.start + int(np.argmax(prof[win]))
    level = 0.5 * float(prof[k])
    if prof[k] < MIN_TICK_CONTRAST:
        return None
    lo, hi = k, k
    while lo > 0 and prof[lo - 1] >= level:
        lo -= 1
    while hi < len(prof) - 1 and prof[hi + 1] >= level:
        hi += 1
    if lo == 0 or hi == len(prof) - 1:  # runs out of the window: not a tick's ends
        return None

    def cross(i: int, j: int) -> float:  # between sample i (above half) and j (below)
        t = (prof[i] - level) / max(float(prof[i] - prof[j]), 1e-6)
        return float(rs[i] + (rs[j] - rs[i]) * t)

    return cross(lo, lo - 1), cross(hi, hi + 1)


def matched_ends(lo: Refined, hi: Refined, clicked_lo, clicked_hi) -> tuple[Refined, Refined]:
    """Both end marks are major ticks of one print and look alike: a refined tick much
    fainter than the other end's (``END_MATCH``) is a label's edge or glare next to a tick
    that the needle hides, and that click is kept."""
    if lo.ok and hi.ok:
        if lo.contrast < END_MATCH * hi.contrast:
            return _kept(clicked_lo, "end mark much fainter than the other end's"), hi
        if hi.contrast < END_MATCH * lo.contrast:
            return lo, _kept(clicked_hi, "end mark much fainter than the other end's")
    return lo, hi


def fraction_sigma(frac: float, span_deg: float, r_min: float, r_max: float,
                   sig_min_px: float, sig_max_px: float, sig_pivot_px: float,
                   sig_needle_deg: float, off_min_deg: float | None = None,
                   off_max_deg: float | None = None) -> float:
    """1-sigma uncertainty of the scale fraction from the points' uncertainties: the end
    marks' angles (across their radius) weigh with 1 - f and f.

    The pivot's error: without ``off_min_deg`` / ``off_max_deg`` it counts in full with
    each end mark, as if the two were independent.  With them (each end mark's image angle
    about the pivot less the needle's), the pivot is the one moved onto the needle's fitted
    line, so only its error along that line remains, and it is one error for both marks: a
    shift ``e`` along the needle turns the ray to a mark at ``phi`` from the needle by
    ``e sin(phi) / r``, and the fraction ``f = (a - a_min) / (a_max - a_min)`` by
    ``-e ((1 - f) sin(phi_min) / r_min + f sin(phi_max) / r_max) / span``.  A mark in the
    needle's direction (a needle resting at the minimum) gains nothing from it, and on a
    scale symmetric about the needle the two marks' turns cancel."""
    f = min(max(frac, 0.0), 1.0)
    if off_min_deg is None or off_max_deg is None:
        s_min = math.degrees(math.hypot(sig_min_px, sig_pivot_px) / max(r_min, 1.0))
        s_max = math.degrees(math.hypot(sig_max_px, sig_pivot_px) / max(r_max, 1.0))
        s_piv = 0.0
    else:
        s_min = math.degrees(sig_min_px / max(r_min, 1.0))
        s_max = math.degrees(sig_max_px / max(r_max, 1.0))
        s_piv = math.degrees(sig_pivot_px * abs(
            (1 - f) * math.sin(math.radians(off_min_deg)) / max(r_min, 1.0)
            + f * math.sin(math.radians(off_max_deg)) / max(r_max, 1.0)))
    return math.sqrt(((1 - f) * s_min) ** 2 + (f * s_max) ** 2 + s_piv ** 2
                     + sig_needle_deg ** 2) / max(span_deg, 1e-6)
