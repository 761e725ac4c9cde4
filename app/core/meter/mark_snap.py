"""An end mark found coarsely (by the keypoint network) made precise on its printed tick.

The network (:mod:`.keypoints`) puts a scale's end mark within a few pixels, with an error
scale ``sigma`` of its own; a printed tick is located far more finely.  This module looks
for the end mark's tick in the image, in the network's uncertainty region, and moves the
mark onto it only when the evidence is unambiguous:

1. the ring at the mark's radius about the pivot is unwrapped along the arc, over the
   region ``SNAP_K * sigma`` either side of the mark and a gap of :data:`GAP_PX` (at least
   the region's width) beyond it, outward (away from the scale);
2. each sample is compared with its row's median over the strip (the face there); the
   ticks' polarity (dark on a light face or light on a dark one) is the side of the face
   whose extremes reach furthest; a column is a tick's where most of the band's rows
   stand out by half the strip's contrast;
3. runs of such columns no wider than :data:`MAX_WIDTH_FRAC` of the radius are ticks; a
   tick's position is its run's contrast-weighted centre, its error scale
   :data:`TICK_SIGMA_PX` or a quarter of its width, whichever is larger; the end tick must
   be a radial line (its band's inner and outer thirds at one position, within
   :data:`STRAIGHT_PX`), not the curved edge of a dot or ring drawn as an end mark, and
   stand alone (the face either side of it, as wide as the tick, bare), not be the edge
   of a filled band;
4. the end mark is the outermost tick of the comb: the outermost tick within the region
   whose ring beyond it, to the gap's far end, holds no other tick.  It is taken only when
   exactly one tick meets that (the region holds a tick, and the gap is bare), and only
   when the strip is not where the needle may lie (the caller passes the needle's
   direction and its doubt), where a needle at the stop pin would pass for the end tick;
5. where no lone radial tick is found so (the mark is a dot or a diamond, or the scale's arc
   line or a zone joins the end tick, so that the face beside it is not bare), the mark
   is looked for row by row instead (:func:`_symmetric_mark`): a solid mark symmetric
   about a radial line, crossing the ring, with bare face beyond it; its position is the
   centre of its rows' outermost runs where it stands alone.  On the tuning families'
   generated gauges (the bench's seeds 1 and 2) every such move from a network mark
   within three of its error scales of the true mark ended within 0.9 of its new one.

Otherwise the network's mark stands, with its own error scale (the caller keeps refusing
where that is too wide).  The tick's position along the arc is what is refined; the mark
keeps the network's radius, which does not change its angle about the pivot.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

__all__ = ["snap_end_mark", "SNAP_K"]

SNAP_K = 3.0  # the uncertainty region: this many error scales either side of the mark
GAP_PX = 6.0  # the bare ring looked at beyond the region (px along the arc), at least
STEP_PX = 0.25  # the strip's column step along the arc
BAND_FRAC, BAND_MIN_PX = 0.07, 3.0  # the strip's half-height: share of the radius, px at least
ROW_SHARE = 0.6  # share of the band's rows that must stand out for a tick's column
LEVEL = 0.5  # ... by this share of the strip's contrast
MIN_CONTRAST = 20.0  # grey levels: a fainter strip shows no tick to trust
MAX_WIDTH_FRAC = 0.06  # a tick is no wider than this share of the radius (along the arc)
TICK_SIGMA_PX = 0.5  # a located tick's error scale, at least
BESIDE_SHARE = 0.25  # share of the face beside a tick that may stand out (noise)
STRAIGHT_PX = 0.6  # a tick's inner and outer halves lie this near one arc position


def snap_end_mark(gray: np.ndarray, pivot, mark, sigma_px: float, outward: float,
                  needle_deg=(), needle_doubt_deg: float = 0.0):
    """(mark point on its tick, the tick's error scale in px) or None.

    ``gray``: the image (grey, uint8 or float); ``pivot``, ``mark``: the network's points
    (px); ``sigma_px``: the mark's error scale; ``outward``: +1 where the scale's outside
    lies clockwise of the mark (the maximum mark of a clockwise scale), -1 anticlockwise;
    ``needle_deg``: the directions the needle may lie in (clockwise from up, image; its tip,
    and its tail's where that is long), and their doubt in degrees: a strip that may hold
    the needle is not searched."""
    px, py = float(pivot[0]), float(pivot[1])
    dx, dy = float(mark[0]) - px, float(mark[1]) - py
    r = math.hypot(dx, dy)
    if r < 10.0 or not (sigma_px > 0.0):
        return None
    a0 = math.atan2(dx, -dy)  # clockwise from up (rad)
    w = SNAP_K * sigma_px
    gap = max(GAP_PX, 2.0 * w)
    # arc coordinate s (px, clockwise positive) from the mark: the strip's columns
    s_in, s_out = (-w, w + gap) if outward > 0 else (-w - gap, w)
    s = np.arange(s_in, s_out + STEP_PX / 2, STEP_PX)
    lo, hi = math.degrees(a0 + s[0] / r), math.degrees(a0 + s[-1] / r)
    mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    for nd in np.atleast_1d(needle_deg):
        if abs((float(nd) - mid + 180.0) % 360.0 - 180.0) <= half + needle_doubt_deg:
            return None
    band = max(BAND_MIN_PX, BAND_FRAC * r)
    rad = np.arange(r - band, r + band + 0.5, 0.5)
    ang = a0 + s / r
    xs = (px + rad[:, None] * np.sin(ang)[None, :]).astype(np.float32)
    ys = (py - rad[:, None] * np.cos(ang)[None, :]).astype(np.float32)
    h, wd = gray.shape[:2]
    if xs.min() < 0 or ys.min() < 0 or xs.max() > wd - 1 or ys.max() > h - 1:
        return None
    strip = cv2.remap(np.asarray(gray, np.float32), xs, ys, cv2.INTER_LINEAR)
    got = _radial_tick(strip, s, w, outward, r)
    if got is None:
        got = _symmetric_mark(strip, s, w, outward, r)
    if got is None:
        return None
    c, sigma = got
    a = a0 + c / r
    return (px + r * math.sin(a), py - r * math.cos(a)), sigma


def _radial_tick(strip: np.ndarray, s: np.ndarray, w: float, outward: float, r: float):
    """(arc position, error scale) of the end tick by steps 2-4 (a radial line across most
    of the band's rows, standing alone), or None."""
    dev = strip - np.median(strip, axis=1, keepdims=True)
    lo_q, hi_q = np.percentile(dev, [1.0, 99.0])
    sign = -1.0 if -lo_q > hi_q else 1.0  # dark ticks on a light face, or light on dark
    dev *= sign
    contrast = max(-lo_q, hi_q)
    if contrast < MIN_CONTRAST:
        return None
    up = (dev > LEVEL * contrast).mean(axis=0) >= ROW_SHARE
    ticks = _runs(up, np.clip(dev, 0.0, None).sum(axis=0), s, MAX_WIDTH_FRAC * r, outward)
    if ticks is None:
        return None
    inside = [t for t in ticks if abs(t[0]) <= w]
    if not inside:
        return None
    # the outermost tick in the region; nothing beyond it to the gap's end
    c, wdt, ia, ib = max(inside, key=lambda t: outward * t[0])
    if any(outward * (t[0] - c) > 0 for t in ticks) or not _straight(dev, s, ia, ib) \
            or not _bare_beside(dev > LEVEL * contrast, ia, ib):
        return None
    return c, max(TICK_SIGMA_PX, 0.25 * wdt)


BLOB_WIDTH_FRAC = 0.11  # a symmetric end mark is no wider than this share of the radius
MARK_ROWS = 6  # ... seen alone in at least this many of the band's rows (3 px)
ROW_CENTRE_PX = 1.0  # each of those rows' centres this near their median


def _symmetric_mark(strip: np.ndarray, s: np.ndarray, w: float, outward: float, r: float):
    """(arc position, error scale) of an end mark that is not a lone radial line: a dot, a
    diamond or a tick that the scale's arc line or a zone joins on the inside.  Row by row
    (each a radius) the outermost print is found; where it is a short run, not cut by the
    strip's inner end, its centre is the mark's there.  Taken only when

    - the face beyond the region (the gap, whose rows give the face's level) is bare: no
      row's print reaches more than a pixel beyond the mark's outer edge;
    - the mark is seen alone in :data:`MARK_ROWS` of the band's rows or more, at least two
      of them either side of the band's middle (it crosses the ring the network put the mark
      on, as an end mark does);
    - its rows' centres agree (each within :data:`ROW_CENTRE_PX` of their median, the inner
      and outer halves' means within :data:`STRAIGHT_PX`): it is symmetric about a radial
      line, as a dot, a diamond or a tick is, and a wedge is not;
    - its centre lies in the region, and no hole (face enclosed by print) lies near it:
      the rows through a ring's hole show its outer wall as a short straight run.

    Its error scale is a quarter of its width (:data:`TICK_SIGMA_PX` at least)."""
    if outward < 0:  # the outside always towards the higher columns
        strip, s = strip[:, ::-1], -s[::-1]
    beyond = s > w
    if beyond.sum() < 8:
        return None
    dev = strip - np.median(strip[:, beyond], axis=1, keepdims=True)
    lo_q, hi_q = np.percentile(dev, [1.0, 99.0])
    dev *= -1.0 if -lo_q > hi_q else 1.0
    contrast = max(-lo_q, hi_q)
    if contrast < MIN_CONTRAST:
        return None
    hot = dev > LEVEL * contrast
    # single pixels of noise are no print
    hot &= cv2.boxFilter(hot.astype(np.float32), -1, (3, 3), normalize=False) >= 3.0
    weight = np.clip(dev, 0.0, None)
    n_rows, n = hot.shape
    col = np.arange(n)
    seen = hot.any(axis=1)
    # each row's outermost print (o) and the start of its run (a: after the last face
    # column before o; 0 where the run is cut by the strip's inner end)
    o = n - 1 - np.argmax(hot[:, ::-1], axis=1)
    face = ~hot & (col[None, :] <= o[:, None])
    a = np.where(face.any(axis=1), n - np.argmax(face[:, ::-1], axis=1), 0)
    width = (o - a + 1) * STEP_PX
    # rows of a short run, not cut by the inner end (the arc line, a zone) nor too wide
    ok = seen & (a > 0) & (width <= BLOB_WIDTH_FRAC * r)
    if np.count_nonzero(ok) < MARK_ROWS:
        return None
    wt = np.where((col[None, :] >= a[:, None]) & (col[None, :] <= o[:, None]), weight, 0.0)
    w_row = wt.sum(axis=1)
    centre = (wt * s[None, :]).sum(axis=1) / np.maximum(w_row, 1e-9)
    c0 = float(np.median(centre[ok]))
    mark = ok & (np.abs(centre - c0) <= ROW_CENTRE_PX)
    js = np.flatnonzero(mark)
    if len(js) < MARK_ROWS or min((js < n_rows // 2).sum(), (js > n_rows // 2).sum()) < 2:
        return None  # too little of it alone, or not across the ring
    if s[o[seen]].max() > s[o[mark]].max() + 1.0:
        return None  # print beyond the mark: it is no end
    cs, ws = centre[mark], w_row[mark]
    half = js < np.median(js)
    if half.all() or not half.any():
        return None
    inner_c = float((cs[half] * ws[half]).sum() / ws[half].sum())
    outer_c = float((cs[~half] * ws[~half]).sum() / ws[~half].sum())
    if abs(inner_c - outer_c) > STRAIGHT_PX:
        return None
    c = float((cs * ws).sum() / ws.sum())
    if abs(c) > w or _hole_near(hot, s, c, BLOB_WIDTH_FRAC * r):
        return None
    width = float(np.median(width[mark]))
    return c * (1.0 if outward > 0 else -1.0), max(TICK_SIGMA_PX, 0.25 * width)


HOLE_CELLS = 8  # strip cells (0.5 px x 0.25 px) of face enclosed by print: a hole (1 px²)


def _hole_near(hot: np.ndarray, s: np.ndarray, c: float, reach: float) -> bool:
    """Whether face enclosed by print (a hole: not joined to the strip's edge) lies within
    ``reach`` px of the arc position ``c``: the mark is a ring or a numeral's loop, whose
    outer wall would pass for a solid mark in the rows through its hole."""
    n, lab = cv2.connectedComponents((~hot).astype(np.uint8), connectivity=4)
    if n <= 2:
        return False
    edge = np.unique(np.concatenate([lab[0], lab[-1], lab[:, 0], lab[:, -1]]))
    near = np.abs(s - c) <= reach
    inner = lab[:, near]
    for k in range(1, n):
        if k in edge:
            continue
        if (inner == k).sum() >= HOLE_CELLS:
            return True
    return False


def _runs(up: np.ndarray, weight: np.ndarray, s: np.ndarray, max_width: float,
          outward: float):
    """[(centre s, width px)] of the runs of ``up``; None if a run is too wide for a tick
    or touches the strip's outer end (it may go on beyond what was looked at).  A run cut
    by the inner end (inside the scale) is left out."""
    d = np.diff(np.concatenate([[0], up.astype(np.int8), [0]]))
    starts, ends = (d == 1).nonzero()[0], (d == -1).nonzero()[0]
    out = []
    for a, b in zip(starts, ends, strict=True):
        if (a == 0 and outward > 0) or (b == len(up) and outward < 0):
            continue  # cut by the inner end: a tick inside the scale
        if a == 0 or b == len(up):
            return None
        width = (b - a) * STEP_PX
        if width > max_width:
            return None
        wt = weight[a:b]
        out.append((float((wt * s[a:b]).sum() / max(wt.sum(), 1e-9)), width, int(a), int(b)))
    return out


def _bare_beside(hot: np.ndarray, a: int, b: int) -> bool:
    """Whether the face either side of the run ``a:b`` (as wide as the run, a pixel at
    least) is bare: a tick stands alone, not at the edge of a filled band or a ring."""
    k = max(int(round(1.0 / STEP_PX)), b - a)
    sides = (hot[:, max(0, a - k - 1):max(0, a - 1)], hot[:, b + 1:b + k + 1])
    return all(x.size > 0 and x.mean() < BESIDE_SHARE for x in sides)


def _straight(dev: np.ndarray, s: np.ndarray, a: int, b: int) -> bool:
    """Whether the run ``a:b`` (columns, a margin added) lies at one arc position in the
    band's inner and outer halves: a radial line, not the curved edge of a dot or ring."""
    a, b = max(0, a - 2), min(dev.shape[1], b + 2)
    third = dev.shape[0] // 3
    at = []
    for rows in (dev[:third, a:b], dev[-third:, a:b]):
        wt = np.clip(rows, 0.0, None).sum(axis=0)
        if wt.sum() <= 0.0:
            return False
        at.append(float((wt * s[a:b]).sum() / wt.sum()))
    return abs(at[0] - at[1]) <= STRAIGHT_PX
