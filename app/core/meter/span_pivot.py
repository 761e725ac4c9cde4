"""The pivot where the needle's line meets the points from which the end marks span the arc.

The angles path (:mod:`.angles`) unwraps the dial about the centre of the ring of scale
marks.  Where that ring's fit says little (marks running through the band's rows fit a
circle about any start, :func:`.ring_centre.ring_centre`), the centre stays where the fit
started, a few pixels off the pivot.  About a centre off the pivot along the gap's axis
both end marks turn inward or outward together, and the arc they bound misses the
profile's span; a short arc's comb of ticks only stretches, so the comb's centre
(:mod:`.comb_centre`) cannot move it, and a hub cap that is no circle gives no third try.

Two facts of the dial still place the pivot: it lies on the needle's line (the needle
turns about it), and from it the two end marks lie the profile's span apart (the scale is
printed about it).  The points from which a chord is seen under a given angle form a
circle's arc (the inscribed angle theorem); :func:`span_pivot` intersects the needle's line
with it, near the needle's own point nearest the ring's centre.  The second constraint
fixes the pivot along the gap's axis, the first across the needle, so the two meet at an
angle wherever the needle lies within a right angle of the arc's middle.

The construction uses the end marks' angles up: about the pivot found they match the span
by design, so it verifies nothing by itself.  The caller (:func:`.angles.read_by_angles`)
therefore finds the scale's end marks again about it and asks the learned end marks
(:mod:`.keypoints`), an estimate that shares no step with the classical ones, to confirm
each of them (:func:`learned_ends_agree`); a classical end mark a tick off would otherwise
be taken for the pivot's slide.
"""

from __future__ import annotations

import math

import numpy as np

from .learned_checks import learned_ends_agree

__all__ = ["span_pivot", "pivot_doubt_px", "span_arc", "SEARCH_PX"]

SEARCH_PX = 8.0  # the pivot is looked for this far along the needle's line either way
_STEP_PX = 0.25  # the scan's step along the line before the root is refined


def _angle_about(px: np.ndarray, py: np.ndarray, m) -> np.ndarray:
    """Image angle (deg, clockwise from up) of the point ``m`` seen from points (px, py)."""
    return np.degrees(np.arctan2(m[0] - px, -(m[1] - py)))


def _ring_point(c, a_deg: float, r: float) -> tuple[float, float]:
    a = math.radians(a_deg)
    return (c[0] + r * math.sin(a), c[1] - r * math.cos(a))


def span_pivot(c, a_lo: float, a_hi: float, radius: float, span: float, q, needle_deg: float,
               search_px: float = SEARCH_PX) -> tuple[float, float] | None:
    """The point on the needle's line (through ``q``, direction ``needle_deg``) from which
    the two end marks, seen at image angles ``a_lo`` and ``a_hi`` (clockwise, ``a_hi`` the
    later) on the ring of ``radius`` about ``c``, lie ``span`` deg apart clockwise; the one
    nearest ``q`` within ``search_px``, or None where the line meets no such point there."""
    m_lo, m_hi = _ring_point(c, a_lo, radius), _ring_point(c, a_hi, radius)
    ux, uy = math.sin(math.radians(needle_deg)), -math.cos(math.radians(needle_deg))

    def miss(s: np.ndarray) -> np.ndarray:
        px, py = q[0] + s * ux, q[1] + s * uy
        seen = (_angle_about(px, py, m_hi) - _angle_about(px, py, m_lo)) % 360.0
        return seen - span

    s = np.arange(-search_px, search_px + 1e-9, _STEP_PX)
    f = miss(s)
    cross = np.nonzero(np.signbit(f[:-1]) != np.signbit(f[1:]))[0]
    # (a jump through the wrap of 360 deg is no root: the seen angle is continuous there)
    cross = [i for i in cross if abs(f[i] - f[i + 1]) < 90.0]
    if not cross:
        return None
    i = min(cross, key=lambda k: abs(s[k] + _STEP_PX / 2.0))
    lo, hi = float(s[i]), float(s[i + 1])
    f_lo = float(f[i])
    for _ in range(30):  # bisection of the bracketed root
        mid = 0.5 * (lo + hi)
        f_mid = float(miss(np.array([mid]))[0])
        if (f_mid < 0) == (f_lo < 0):
            lo, f_lo = mid, f_mid
        else:
            hi = mid
    t = 0.5 * (lo + hi)
    return (q[0] + t * ux, q[1] + t * uy)


def pivot_doubt_px(c, a_lo: float, a_hi: float, radius: float, span: float, q,
                   needle_deg: float, p, step_deg: float) -> float:
    """How far the pivot of :func:`span_pivot` (``p``) moves when the end marks' span seen
    about ``c`` is a polar column (``step_deg``) wider or narrower, as an end mark placed a
    column off would make it: the construction's own doubt, in px.  Where either change
    leaves the line without such a point, the whole search (:data:`SEARCH_PX`)."""
    worst = 0.0
    for d in (-step_deg / 2.0, step_deg / 2.0):
        p2 = span_pivot(c, a_lo - d, a_hi + d, radius, span, q, needle_deg)
        if p2 is None:
            return SEARCH_PX
        worst = max(worst, math.hypot(p2[0] - p[0], p2[1] - p[1]))
    return worst


def span_arc(darkf: np.ndarray, thr: float, prof, crop: np.ndarray, c, nf, arc, start: float,
             span: float, kp, strip_of, tol_deg: float, step_deg: float):
    """The dial's turn about :func:`span_pivot`'s pivot, where the arc about the ring's
    centre ``c`` was refused because its two end marks (``arc``) miss the profile's span:
    (arc fit, the needle about the new pivot, the construction's doubt px), or None.  The
    needle ``nf`` (about ``c``) gives the line; about the new pivot the needle is found
    again (``strip_of(nf)`` hides it from the marks), the arc must be fitted anew with both
    end marks found, and the learned keypoints ``kp`` must put each end mark within
    ``tol_deg`` of where that fit does."""
    from .arc_fit import fit_profile_arc
    from .dial import FACE_RADIUS
    from .needle import find_needle

    if kp is None or arc.candidate_rho is None or not nf.ok:
        return None
    a_lo = start + arc.candidate_rho - arc.mismatch_deg / 2.0
    a_hi = start + span + arc.candidate_rho + arc.mismatch_deg / 2.0
    p = span_pivot(c, a_lo, a_hi, arc.radius, span, nf.pivot_xy, nf.angle_deg)
    if p is None or math.hypot(p[0] - c[0], p[1] - c[1]) > SEARCH_PX:
        return None
    nf2 = find_needle(crop, p, 0.8 * FACE_RADIUS, needle=prof.needle,
                      ignore_colour=prof.ignore_colour, straight_rivals=True)
    if not nf2.ok:
        return None
    arc2 = fit_profile_arc([(darkf, thr)], p, FACE_RADIUS, strip_of(nf2), start, span)
    if arc2.rho_deg is None or arc2.ends < 2:
        return None
    if not learned_ends_agree(kp, p, prof.min_angle_deg + arc2.rho_deg,
                              prof.max_angle_deg + arc2.rho_deg, tol_deg):
        return None
    doubt = pivot_doubt_px(c, a_lo, a_hi, arc.radius, span, nf.pivot_xy, nf.angle_deg, p,
                           step_deg)
    return arc2, (float(p[0]), float(p[1])), nf2, doubt
