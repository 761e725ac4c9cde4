"""The pivot that makes the scale's ticks evenly spaced: the centre refined from the comb.

A linear scale's ticks are printed at even angles about the pivot, phi_k = phi_0 + k p.
Seen about a centre off the pivot by delta (image px), a tick at radius r appears turned
by -(delta . v(phi)) / r, where v(phi) = (cos phi, sin phi) is the clockwise tangent at
phi (first order in |delta| / r): the comb of ticks is bent by a sine of one period round
the dial.  Its angles therefore carry the centre's error, and a linear least-squares fit
of the ticks' measured angles

    theta_k = phi_0 + k p - (delta_x cos theta_k + delta_y sin theta_k) / r
              + a sin 2 theta_k + b cos 2 theta_k

in (phi_0, p, delta_x, delta_y, a, b) gives it (a and b: a residual stretch of the crop,
which turns angles with period two), independent of the ring's radius.  A circle
fitted to the marks' ends (:func:`.ring_centre.ring_centre`) is not: over an arc with a gap the
fitted radius and the centre's position along the gap's axis move together, so a radius
a little off (blur, ticks of two lengths, residual perspective) slides the centre toward
or away from the gap, and both end marks then seem to move inward (or outward) together.

:func:`comb_centre` unwraps the dial about a first centre, takes the ring of short radial
strokes (:func:`.tick_band.tick_rings`), measures each thin tick's angle (the
grey-weighted column over the ring's radii, a fraction of a 0.5 deg column), numbers the
ticks by the comb's pitch (consecutive gaps rounded to whole pitches: a tick hidden by the
needle or a numeral leaves a gap of two), fits the model above trimmed of ticks that miss
it (numerals, a tick crossed by print) and refits about the new centre.  A scale that is
not an even comb (a non-linear scale's ticks) leaves residuals larger than a tick's
measurement and is no estimate.
"""

from __future__ import annotations

import math

import numpy as np

from .arc_fit import ring_rows
from .scale import N_ANG, polar
from .tick_band import STROKE_ROWS

STEP = 360.0 / N_ANG
MIN_TICKS = 12  # ticks whose angles fix a centre
MAX_TICK_COLS = 6  # a thin tick is at most this many polar columns wide
MIN_ARC_DEG = 150.0  # the ticks spread over at least this much of the circle
MAX_RMS_DEG = 0.2  # the comb's residuals: larger, the ticks are not an even comb
MAX_SHIFT_PX = 8.0  # a centre this far from the first one is no refinement
PITCH_TOL = 0.2  # a gap between ticks is a whole number of pitches within this share


def comb_centre(darkf: np.ndarray, thr: float, centre, face_r: float,
                hidden: np.ndarray | None = None, rounds: int = 2, stretch: bool = False,
                max_se: float = 0.5):
    """((x, y), standard error px, ticks used) of the centre about which the ring's ticks
    form an even comb (see the module's docstring), starting from ``centre``, or None.
    ``darkf``: the dark-marks image (float32), ``thr`` its threshold; ``hidden``: the
    needle's region as a float32 image (unknown evidence), or None.  ``stretch``: fit the
    period-two terms too; ``max_se``: a centre known less well (px) is no refinement."""
    c = np.array([float(centre[0]), float(centre[1])])
    out = None
    for _ in range(rounds):
        found = _fit(darkf, thr, c, face_r, hidden, stretch)
        if found is None:
            return None
        delta, se, n = found
        if se > max_se:
            return None
        c = c - delta
        if math.hypot(c[0] - centre[0], c[1] - centre[1]) > MAX_SHIFT_PX:
            return None
        out = ((float(c[0]), float(c[1])), se, n)
    return out


def tick_angles(pol: np.ndarray, thr: float, hid_cols: np.ndarray, rows: slice):
    """Angles (deg) of the thin ticks crossing the middle of the rows ``rows`` of the polar
    image ``pol`` (grey-weighted over all those rows, to a fraction of a column), ticks
    touching ``hid_cols`` left out."""
    sub = pol[rows] > thr
    w = np.clip(pol[rows] - thr, 0.0, None) * sub
    m = sub.shape[0] // 2  # the ring's middle radii, which every tick of it crosses
    lit = sub[max(0, m - 1): m + 2].all(axis=0)
    n = len(lit)
    out = []
    for a in np.flatnonzero(lit & ~np.concatenate((lit[-1:], lit[:-1]))):  # (np.roll(lit, 1))
        z = a
        while lit[(z + 1) % n] and z - a <= MAX_TICK_COLS:
            z += 1
        if z - a + 1 > MAX_TICK_COLS:
            continue
        cols = np.arange(a - 1, z + 2) % n
        if hid_cols[cols].any():
            continue
        ww = w[:, cols].sum(axis=0)
        out.append(((a - 1) + float((ww * np.arange(len(cols))).sum() / ww.sum())) * STEP)
    return np.array(out) % 360.0


def _fit(darkf, thr, c, face_r, hidden, stretch=False):
    """(delta, standard error, ticks) of the comb's fit about ``c``, or None."""
    pol, rs = polar(darkf, c, 0.45 * face_r, 0.97 * face_r)
    rows_of = ring_rows(pol, thr)
    b = rows_of.b
    if hidden is not None:
        hm, _ = polar(hidden, c, 0.45 * face_r, 0.97 * face_r)
        hid_cols = (hm > 0.05).any(axis=0)
    else:
        hid_cols = np.zeros(b.shape[1], bool)
    rings = rows_of.tick_rows()  # (where they lie does not depend on the needle)
    if not rings:
        return None
    th, r = np.zeros(0), 0.0
    for lo, hi in rings:  # the ring with the most thin ticks
        t = tick_angles(pol, thr, hid_cols, slice(lo, min(b.shape[0], hi + STROKE_ROWS)))
        if len(t) > len(th):
            th, r = t, float(rs[(lo + hi) // 2])
    if len(th) < MIN_TICKS:
        return None
    # in order round the ring from the largest gap (the scale's own)
    th = np.sort(th)
    gaps = np.diff(np.concatenate([th, [th[0] + 360.0]]))
    first = (int(np.argmax(gaps)) + 1) % len(th)
    th = np.concatenate([th[first:], th[:first] + 360.0])
    d = np.diff(th)
    if 360.0 - float(gaps.max()) < MIN_ARC_DEG:
        return None
    pitch = float(np.median(d))
    if pitch <= 2 * STEP:
        return None
    steps = d / pitch
    k_step = np.round(steps)
    if np.any(k_step < 1):
        return None
    # gaps that are no whole number of pitches: a numeral's stroke; cut it out
    ok_gap = np.abs(steps - k_step) <= PITCH_TOL
    k = np.concatenate([[0.0], np.cumsum(k_step)])
    keep = np.ones(len(th), bool)
    keep[1:] &= ok_gap | np.r_[ok_gap[1:], True]
    t = np.radians(th)
    # the period-two terms: a residual stretch of the crop (a tilt the rim's ellipse left)
    # turns angles by a sin 2 theta + b cos 2 theta; fitted too, so that it is not taken
    # for the centre's offset (over a short arc the two look alike: the error says so)
    cols = [np.ones_like(t), k, -np.cos(t) / r, -np.sin(t) / r]
    a_mat = np.column_stack(cols + ([np.sin(2 * t), np.cos(2 * t)] if stretch else []))
    x = None
    for _ in range(4):
        if keep.sum() < MIN_TICKS:
            return None
        x, *_ = np.linalg.lstsq(a_mat[keep], t[keep], rcond=None)
        res = t - a_mat @ x
        rms = math.sqrt(float(np.mean(res[keep] ** 2)))
        new = np.abs(res) < max(np.radians(0.05), 2.5 * rms)
        if np.array_equal(new, keep):
            break
        keep = new
    if math.degrees(rms) > MAX_RMS_DEG or keep.sum() < MIN_TICKS:
        return None
    ak = a_mat[keep]
    ata = ak.T @ ak
    if np.linalg.cond(ata) > 1e12:
        return None
    cov = np.linalg.inv(ata) * rms ** 2 * keep.sum() / max(keep.sum() - a_mat.shape[1], 1)
    se = math.sqrt(float(cov[2, 2] + cov[3, 3]))
    return np.array([x[2], x[3]]), se, int(keep.sum())
