"""The dial's turn from the comb of its tick marks (a finer estimate than the end marks).

A scale's ticks are evenly spaced: the ticks of a linear scale with ``N`` intervals over
the profile's span ``S`` sit at ``a_min + rho + j S / N`` (``j = 0..N``), ``rho`` being the
dial's turn in the picture.  Their positions round the ring of marks therefore tell
``rho`` modulo the pitch ``p = S / N`` very precisely (a circular mean of all the ticks'
phases), without any single mark having to be found: an end mark hidden by the needle, a
stop pin beside the minimum mark or a numeral at an end no longer moves the estimate.

1. **Ticks**: runs of the ring's evidence standing above its local floor (a printed arc
   or a colour zone under the ticks raises the floor, not the runs), short enough to be a
   tick, away from the needle's hidden columns; a run's position is its weighted centre.
2. **Pitch**: the smallest ``N`` whose comb holds the ticks in phase (resultant length of
   the phases ``2 pi t N / S``).  A comb of ``N / k`` or ``N + 1`` intervals spreads the
   phases and fails, so the smallest ``N`` that holds them is the ticks' own.
3. **Phase**: the circular mean of the phases of the ticks that agree with it gives
   ``rho`` modulo ``p``; their spread gives its standard error (two of them bound it).
   A profile's span a little off the dial's shows as a drift of the ticks off the comb
   along the arc: a drift over a quarter pitch is no comb, a smaller one adds half of
   itself to the error.
4. **Which tooth**: the candidate turns ``rho + k p`` are scored by the comb's teeth that
   meet a tick inside the arc, less twice the teeth inside that meet none where the ring
   is seen, less twice those that meet a tick in the gap beyond the ends.
   Only a best candidate ahead of every other by a clear margin, with at least one end
   verified (its tooth meets a tick and the ring beyond it is seen and bare), is kept: a
   scale whose extent does not say where it ends (both ends hidden, ticks all round, print
   against an end) gives none.  Only the true turn can verify an end (a comb a tooth out
   puts that end's tooth in the bare gap, or has the true end tick beyond it), so where
   the scores leave candidates within the margin because one end is under the needle, the
   one candidate that verifies the other end is kept.

The reading's bound then carries the phase's error instead of the end marks' mismatch.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import cv2
import numpy as np

__all__ = ["CombFit", "comb_turn", "tick_positions"]

log = logging.getLogger(__name__)

FLOOR_DEG = 5.0  # the evidence's local floor: its minimum within this either side
PEAK_MIN = 0.3  # a tick stands this far above the floor (share of the ring's rows)
SHORT_DEG = 6.0  # a run up to this long is a tick (a wide major tick too)
MIN_PITCH_DEG = 1.5  # finer combs are not resolved by the polar image
MIN_TICKS = 6  # ticks in phase needed for a comb
R_MIN = 0.7  # resultant length of the phases that makes a comb
INLIER_FRAC = 0.7  # share of the arc's ticks that must lie on the comb
PHASE_TOL = 0.2  # a tick lies on a tooth within this share of the pitch
HIT_TOL_DEG = 0.8  # ... and, to tell a tick from a mark beside the comb, within this
SCORE_MARGIN = 2.0  # the chosen tooth leads every other by this score
GAP_TEETH = 3  # teeth looked at in the gap beyond each end
GAP_CLEAN_DEG = 6.0  # an end mark has this much bare ring beyond it (from half a pitch out)
DRIFT_MAX = 0.25  # share of the pitch the ticks may drift off the comb along the arc
NEAR_HIDDEN_DEG = 2.0  # an end tooth this close to the needle's columns counts as unseen
MIN_FILL = 0.5  # share of the chosen comb's seen teeth that must meet a tick
COMB_BLOCK = 16  # pitches tried at once, coarsest first
TIE_FIT = 0.8  # a tie is settled by a verified end only for a comb scoring this per seen tooth


@dataclass(frozen=True)
class CombFit:
    """The comb's turn (deg), its error bound (two standard errors of the phase and half
    the drift along the arc), the pitch, the ends it verified."""

    rho_deg: float
    err_deg: float
    pitch_deg: float
    ends: int
    margin: float
    n_ticks: int


def tick_positions(e: np.ndarray, known: np.ndarray, step_deg: float) -> np.ndarray:
    """Column positions (float) of the ticks in one ring's circular evidence ``e``."""
    return tick_runs(e, known, step_deg)[0]


def _floor(e: np.ndarray, step_deg: float) -> np.ndarray:
    """The evidence's local floor: its minimum within :data:`FLOOR_DEG` either side.

    (``scipy.ndimage.minimum_filter1d(e, 2 h + 1, mode="wrap")``, the same values: an
    erosion, i.e. each column's minimum over its window, of a copy of ``e`` wrapped round
    by ``h`` columns at each end; without scipy, whose import costs ≈ 0.6 s on a reader's
    first comb.)"""
    h = int(round(FLOOR_DEG / step_deg))
    n = len(e)
    got = _WRAPS.get((n, h))
    if got is None:  # the wrapped columns and the window depend on n and h alone
        got = _WRAPS[(n, h)] = (np.arange(-h, n + h) % n, np.ones((1, 2 * h + 1), np.uint8))
    wrapped = e.take(got[0])
    if wrapped.dtype not in (np.float32, np.float64):  # (OpenCV erodes no int64 or bool)
        return np.lib.stride_tricks.sliding_window_view(wrapped, 2 * h + 1).min(axis=1)
    return cv2.erode(wrapped[None, :], got[1], borderType=cv2.BORDER_REPLICATE)[0, h:n + h]


_WRAPS: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}


def tick_runs(e: np.ndarray, known: np.ndarray, step_deg: float,
              floor: np.ndarray | None = None):
    """Column positions (float) of the ticks in one ring's circular evidence ``e`` and
    their widths (columns).  ``floor``: ``_floor(e, step_deg)`` if the caller has it."""
    n = len(e)
    if floor is None:
        floor = _floor(e, step_deg)
    up = ((e - floor) >= PEAK_MIN) & known
    if not up.any() or up.all():
        return np.zeros(0), np.zeros(0)
    # runs of ``up`` round the circle, starting after a column that is not up
    first = int((~up).nonzero()[0][0])
    order = (np.arange(n) + first) % n
    u = up[order].astype(np.int8)
    d = np.diff(np.concatenate([[0], u, [0]]))
    starts, ends = (d == 1).nonzero()[0], (d == -1).nonzero()[0]
    keep = (ends - starts) <= SHORT_DEG / step_deg
    # a run touching the needle's hidden columns may be cut by it
    keep &= known[(order[starts] - 1) % n] & known[(order[ends - 1] + 1) % n]
    if not keep.any():
        return np.zeros(0), np.zeros(0)
    w = np.concatenate([np.where(u > 0, (e - floor)[order], 0.0), [0.0]])
    idx = np.arange(n + 1, dtype=float)
    sw = np.add.reduceat(w, starts)
    swi = np.add.reduceat(w * idx, starts)
    # reduceat sums up to the next start: the columns between runs weigh 0
    return ((first + swi[keep] / sw[keep]) % n).astype(float), \
        (ends - starts)[keep].astype(float)


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + 180.0) % 360.0 - 180.0


def _coarsest_comb(inside: np.ndarray, span_deg: float):
    """(intervals, resultant) of the coarsest comb of the span that holds the ticks at
    ``inside`` (deg) in phase: the fewest intervals n >= 2 whose phases' resultant
    reaches :data:`R_MIN`, or None.  Tried in blocks of :data:`COMB_BLOCK` pitches from the
    coarsest, stopping at the first block that has one (each pitch's resultant is the
    same, computed alone or with the others)."""
    n_max = int(span_deg / MIN_PITCH_DEG)
    for n0 in range(2, n_max + 1, COMB_BLOCK):
        ns = np.arange(n0, min(n0 + COMB_BLOCK, n_max + 1))
        z = np.exp(2j * np.pi * np.outer(ns, inside) / span_deg).mean(axis=1)
        ok = (np.abs(z) >= R_MIN).nonzero()[0]
        if len(ok):
            return int(ns[ok[0]]), z[ok[0]]
    return None


def comb_turn(e: np.ndarray, known: np.ndarray, step_deg: float, arc_start_deg: float,
              span_deg: float, rho0: float, max_roll: float) -> CombFit | None:
    """The turn from the ticks' comb about the coarse turn ``rho0`` (see the module), or
    None where the ticks do not make an unambiguous comb."""
    floor = _floor(e, step_deg)  # made once: the ticks' runs and the ends' gaps use it
    ticks, widths = tick_runs(e, known, step_deg, floor)
    ticks, widths = ticks * step_deg, widths * step_deg  # deg round the ring
    if len(ticks) < MIN_TICKS:
        return _no("too few ticks (%d)", len(ticks))
    a0 = arc_start_deg + rho0
    rel = (ticks - a0) % 360.0
    margin = min(5.0, 0.1 * span_deg)  # the coarse arc's ends may be a few degrees out
    inside = rel[(rel > margin) & (rel < span_deg - margin)]
    if len(inside) < MIN_TICKS:
        return _no("too few ticks inside the arc (%d)", len(inside))
    first = _coarsest_comb(inside, span_deg)
    if first is None:
        return _no("no pitch holds the ticks in phase")
    n_int, z0 = first
    p = span_deg / n_int
    # the phase from the ticks on the comb (re-fitted once without those off it)
    phase = float(np.angle(z0))
    for _ in range(2):
        off = _wrap((inside - phase / (2 * np.pi) * p) / p * 360.0) / 360.0 * p  # deg
        on = np.abs(off) <= PHASE_TOL * p
        if on.sum() < max(MIN_TICKS, INLIER_FRAC * len(inside)):
            return _no("too few ticks on the comb of %d intervals (%d of %d)", n_int,
                       on.sum(), len(inside))
        phase = float(np.angle(np.exp(2j * np.pi * inside[on] / p).mean()))
    off = _wrap((inside[on] - phase / (2 * np.pi) * p) / p * 360.0) / 360.0 * p
    # a profile's span a little off the dial's makes the ticks drift off the comb along the
    # arc: the drift from end to end must stay small, and half of it is the turn's error
    drift = _slope(inside[on], off) * span_deg
    if abs(drift) > DRIFT_MAX * p:
        return _no("the ticks drift off the comb by %.2f deg", drift)
    # two standard errors of the phase, and half the drift (the ends' share of it)
    err = 2.0 * float(np.std(off) / math.sqrt(on.sum())) + abs(drift) / 2.0
    base = rho0 + phase / (2 * np.pi) * p  # a turn whose teeth meet the ticks
    # which tooth is the minimum mark: score the candidate turns by the scale's extent
    ks = np.arange(math.floor((-max_roll - base) / p), math.ceil((max_roll - base) / p) + 1)
    gap = 360.0 - span_deg
    g = max(1, min(GAP_TEETH, int((gap / 2.0) // p)))
    tol = min(PHASE_TOL * p, HIT_TOL_DEG)
    rhos = base + ks * p
    m_in = np.arange(n_int + 1)
    # teeth of every candidate at once: inside (K x N+1), below and above the arc (K x g)
    t_in = arc_start_deg + rhos[:, None] + p * m_in[None, :]
    t_lo = arc_start_deg + rhos[:, None] - p * np.arange(1, g + 1)[None, :]
    t_hi = arc_start_deg + rhos[:, None] + span_deg + p * np.arange(1, g + 1)[None, :]
    srt = np.sort(ticks % 360.0)
    ext = np.concatenate([srt - 360.0, srt, srt + 360.0])

    def hits(teeth):
        t = teeth % 360.0
        j = np.minimum(np.maximum(ext.searchsorted(t), 1), len(ext) - 1)
        return np.minimum(np.abs(ext[j] - t), np.abs(t - ext[j - 1])) <= tol

    def seen(teeth):
        return known[np.round((teeth % 360.0) / step_deg).astype(int) % len(known)]

    # (the three sets of teeth in one call: each tooth is looked up on its own)
    h_all = hits(np.concatenate((t_in, t_lo, t_hi), axis=1))
    h_in, h_lo, h_hi = h_all[:, :n_int + 1], h_all[:, n_int + 1:n_int + 1 + g], \
        h_all[:, n_int + 1 + g:]
    missed = (~h_in & seen(t_in)).sum(axis=1)
    scores = h_in.sum(axis=1) - 2.0 * (missed + h_lo.sum(axis=1) + h_hi.sum(axis=1))
    # an end is verified by its tooth meeting a tick and by a clean gap beyond it: seen,
    # and no evidence standing above its floor (a blob of print where ticks merged, a stop
    # pin, or ticks the detector missed would stand there).  Only the true turn can verify
    # an end: a comb shifted outwards puts that end's tooth in the bare gap, one shifted
    # inwards has the true end tick beyond it
    lift = e - floor

    def out_edge(tooth: float) -> float:
        # the bare gap begins half a pitch out, or beyond the end tick's own half-width
        # where the end mark is a wide one (a wedge, a tee)
        d = np.abs(_wrap(ticks - tooth))
        j = int(d.argmin())
        return max(0.5 * p, 0.5 * widths[j] + step_deg) if d[j] <= tol else 0.5 * p

    def verified(k: int) -> int:
        a_min = arc_start_deg + rhos[k]
        a_max = a_min + span_deg
        o_lo, o_hi = out_edge(a_min), out_edge(a_max)
        return (int(h_in[k, 0] and _clear(lift, known, step_deg, a_min - o_lo
                                          - GAP_CLEAN_DEG, a_min - o_lo))
                + int(h_in[k, -1] and _clear(lift, known, step_deg, a_max + o_hi,
                                             a_max + o_hi + GAP_CLEAN_DEG)))

    # the candidate the scale's extent favours; candidates it cannot tell apart (within
    # the margin: an end hidden by the needle, a stop pin or a numeral beside the other)
    # are told apart by the ends they verify, and only one of them may verify any
    top = float(scores.max())
    close = (scores > top - SCORE_MARGIN).nonzero()[0]
    ver = {int(k): verified(int(k)) for k in close}
    best_v = max(ver.values())
    winners = [k for k, v in ver.items() if v == best_v]
    if best_v == 0 or len(winners) != 1:
        return _no("no single candidate verifies an end (%s; scores %s)", ver,
                   scores.tolist())
    best = winners[0]
    rest = np.delete(scores, best)
    others_v = [v for k, v in ver.items() if k != best]
    # its lead: over every other candidate by score, or by the ends it alone verifies; the
    # latter only where the extent could not decide because an end is unseen (under the
    # needle): an end that is seen but not verified (the scale going on beyond it, a
    # profile's span shorter than the dial's) leaves the choice open
    lead = float(scores[best] - rest.max()) if len(rest) else math.inf
    if others_v and lead < SCORE_MARGIN:
        # (a tick touching the needle's columns is dropped: within NEAR_HIDDEN_DEG of them
        # an end counts as unseen)
        w = int(math.ceil(NEAR_HIDDEN_DEG / step_deg))
        near = np.arange(-w, w + 1)
        ends_seen = [bool(known[(int(round((t % 360.0) / step_deg)) + near) % len(known)].all())
                     for t in t_in[best, [0, -1]]]
        if best_v < 2 and all(ends_seen):
            return _no("both ends seen, only one verified, within the margin")
        # ... and only for a comb that fits the ticks: its teeth, where the ring is seen,
        # nearly all meet one (a comb of marks that are not ticks scores low everywhere,
        # and a verified end among its candidates means nothing)
        if scores[best] < TIE_FIT * float(seen(t_in[best]).sum()):
            return _no("the comb does not fit the ticks (%.1f of %d)", scores[best],
                       seen(t_in[best]).sum())
        lead = float(SCORE_MARGIN * (best_v - max(others_v)))
    # the comb must be the scale's: most of its teeth where the ring is seen meet a tick (a
    # fine comb laid over a few noisy marks leads its neighbours by a point or two, but
    # its teeth mostly meet nothing)
    n_seen = int(seen(t_in[best]).sum())
    if h_in[best].sum() < MIN_FILL * n_seen:
        return _no("the comb's teeth mostly meet no tick (%d of %d)", h_in[best].sum(), n_seen)
    rho = float(base + ks[best] * p)
    if abs(rho) > max_roll - 2.0:
        return _no("turn %.1f at the edge of the search", rho)
    return CombFit(rho, err, p, best_v, float(lead), int(on.sum()))


def _slope(x: np.ndarray, y: np.ndarray) -> float:
    """The least-squares slope of y on x (``np.polyfit(x, y, 1)[0]``, in closed form about
    the means: the same line, without polyfit's scaled solver); 0 when all x are equal."""
    dx = x - float(np.add.reduce(x)) / len(x)
    sxx = float(dx @ dx)
    return float(dx @ y) / sxx if sxx > 0.0 else 0.0


def _no(why: str, *args) -> None:
    """No comb: the reason is logged (debug)."""
    log.debug("no tick comb: " + why, *args)


def _clear(lift: np.ndarray, known: np.ndarray, step_deg: float, a0: float, a1: float) -> bool:
    """Whether the ring is seen and bare (nothing above its floor) from ``a0`` to ``a1``."""
    cols = np.arange(int(math.floor(a0 / step_deg)), int(math.ceil(a1 / step_deg)) + 1)
    cols %= len(lift)
    return bool(known[cols].all() and (lift[cols] < PEAK_MIN).all())
