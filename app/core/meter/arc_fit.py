"""The dial's turn: the profile's arc slid round the ring of the scale's printed marks.

:func:`fit_profile_arc` is the second estimate of :mod:`.angles` (see its docstring): the
scale's marks lie on a ring, over the profile's arc and not in its gap.  The arc is slid
round that ring's evidence; where it holds the most evidence is the dial's turn, and the
two end marks, found coming in from the gap, each say where the arc begins or ends.  Their
disagreement is the turn's uncertainty.  An end mark is judged by its shape in the polar
image (:mod:`.end_marks`): a tick is a thin stroke along the radius, about as long as the
ring's major ticks; a numeral printed beside it in the gap is passed over, and a thick end
tick, or one merged with a numeral or an arc's corner, is placed by its centre line.
Where the ticks form an even comb, the comb's phase (:mod:`.tick_comb`) gives the turn
instead, to a fraction of a degree, and the end marks only need to say which tooth is the
minimum mark.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import cv2
import numpy as np

from .arc_line import line_rows
from .counts import col_counts, row_counts
from .end_marks import MARK_MARGIN_ROWS, end_mark, radial_lengths
from .scale import N_ANG, angle_diff, polar
from .tick_band import long_columns, ring_evidence, short_runs, tick_ring_rows, tick_rings
from .tick_comb import comb_turn

__all__ = ["ArcFit", "fit_profile_arc", "bands", "mark_level", "ring_rows", "MAX_ROLL_DEG",
           "STEP", "SPAN_MISS"]

MAX_ROLL_DEG = 25.0  # the turns searched; a fit at the edge of the search is refused
STEP = 360.0 / N_ANG  # polar columns, deg
RHO_STEP = 0.1  # deg between the turns tried
SPAN_TOL_DEG = 1.5  # deg: the two end marks' turns must agree within this
EDGE_SLACK_DEG = 1.25  # an arc's end reaches this far beyond its end mark (half a stroke)
PLATEAU_COLS = 0.25  # columns of evidence below the best that count as as good
SPAN_MISS = "the scale's end marks lie"  # the start of the refusal for end marks off the span
NEAR_MISS_DEG = 12.0  # end marks this far off the span: the scale, shifted or cut short
_K5 = np.ones((5, 5), np.uint8)


@dataclass(frozen=True)
class ArcFit:
    """Where the profile's arc sits on the dial: its turn ``rho_deg`` (clockwise, added to
    the profile's angles), which end marks vouch for it, and how far apart their own
    estimates of the turn are (0 when only one end mark was seen)."""

    rho_deg: float | None
    ends: int = 0  # end marks seen (2: both agree; 1: the other hidden by the needle)
    mismatch_deg: float = 0.0  # the two end marks' turns differ by this
    contrast: float = 0.0  # mean evidence inside the arc minus outside it
    radius: float = 0.0  # the evidence ring's radius (px)
    error: str | None = None
    method: str = "ends"  # "ends": the end marks' turns; "comb": the ticks' comb
    turn_err_deg: float = 0.0  # the comb's phase error (deg)
    # how far the end marks' places may be off together (deg), which their mismatch cannot
    # show: see :func:`.end_marks.end_mark`
    ends_err_deg: float = 0.0
    # a refused fit's best guess at the turn (the end marks' mean, or the coarse turn), for
    # telling what a refusal would have read (never read from)
    candidate_rho: float | None = None
    # the ring's evidence the fit was made on, the needle not hidden: (per-column evidence,
    # columns where marks can be seen), for what lies beyond the scale's ends
    # (:func:`.stop_pin.gap_is_bare`)
    ring: tuple | None = field(default=None, compare=False, repr=False)


def bands(b: np.ndarray) -> list[tuple[int, int]]:
    """Candidate rings of radii holding the scale: the band crossed by most dark runs
    (ticks), the band just inside it (major ticks only) and the most covered band (a
    printed arc or colour zones)."""
    r0 = row_counts(b[:, 1:] != b[:, :-1]) / 2.0
    # each row's runs: the fewest of it and its two neighbours (the first and last rows,
    # which lack one, are set to 0)
    runs = r0.copy()
    np.minimum(runs[1:], r0[:-1], out=runs[1:])
    np.minimum(runs[:-1], r0[1:], out=runs[:-1])
    runs[0] = runs[-1] = 0
    out = []
    if runs.max() >= 6:
        top = int(runs.argmax())
        band = runs >= 0.7 * runs.max()
        lo = hi = top
        while lo > 0 and band[lo - 1]:
            lo -= 1
        while hi < len(band) - 1 and band[hi + 1]:
            hi += 1
        out.append((lo, hi))
        hi2 = lo - 1
        while hi2 > 0 and runs[hi2] < 6:
            hi2 -= 1
        lo2 = hi2
        while lo2 > 0 and runs[lo2 - 1] >= 6 and runs[lo2 - 1] >= 0.6 * runs[hi2]:
            lo2 -= 1
        if hi2 - lo2 >= 2 and lo - hi2 < 6:
            out.append((lo2, hi2))
    cover = row_counts(b) / b.shape[1]  # (b.mean(axis=1))
    cover[cover > 0.97] = 0  # a ring dark all round (a bezel edge) has no gap
    top = int(cover.argmax())
    if cover[top] > 0.2:
        out.append((max(0, top - 1), min(len(cover) - 1, top + 1)))
    return out


def percentile(a: np.ndarray, q: float) -> float:
    """``float(np.percentile(a, q))`` of a non-empty 1-D array without NaN (its linear
    method, the same value) by one partition at the two ranks it interpolates between,
    without its general machinery."""
    n = len(a)
    vi = (n - 1) * (q / 100.0)
    lo = int(math.floor(vi))
    hi = min(lo + 1, n - 1)
    # partitioned at the ranks numpy partitions at (first, last, the two): equal values
    # of either sign of zero then land where they land in numpy
    p = np.partition(a, sorted({0, lo, hi, n - 1}))
    x, y = float(p[lo]), float(p[hi])
    t = vi - lo
    d = y - x
    # numpy's interpolation: from the nearer of the two ranks
    return y - d * (1 - t) if t >= 0.5 else x + d * t


def _window_sums(e: np.ndarray, span_cols: float, starts: np.ndarray) -> np.ndarray:
    """Evidence summed over the circular window [s, s + span) for fractional starts s.
    (The window's two ends are interpolated in one call: each point on its own, so the
    same values as two calls.)"""
    n = len(e)
    c = np.empty(3 * n + 1)
    c[0] = 0.0
    np.cumsum(np.concatenate((e, e, e)), out=c[1:])  # (np.tile(e, 3))
    x = _COLUMNS.get(n)
    if x is None:
        x = _COLUMNS[n] = np.arange(3 * n + 1, dtype=float)
    s = starts % n + n
    k = len(s)
    v = np.interp(np.concatenate([s + span_cols, s]), x, c)
    return v[:k] - v[k:]


_COLUMNS: dict[int, np.ndarray] = {}  # the cumulative sums' abscissae, per ring length


class RingRows:
    """The rings of a polar image thresholded at ``thr`` (``b = pol > thr``): :func:`bands`
    of it, its short runs (:func:`.tick_band.short_runs`) and the rows of its rings of ticks
    (:func:`.tick_band.tick_ring_rows`), each made on first use.  ``b`` and the short runs
    are read-only; the row lists are handed out as copies."""

    __slots__ = ("b", "_rings", "_short", "_ticks")

    def __init__(self, pol: np.ndarray, thr: float):
        self.b = pol > thr
        self.b.flags.writeable = False
        self._rings = self._short = self._ticks = None

    def rings(self) -> list[tuple[int, int]]:
        if self._rings is None:
            self._rings = bands(self.b)
        return list(self._rings)

    def short(self) -> np.ndarray:
        if self._short is None:
            self._short = short_runs(self.b, long_columns(STEP))
            self._short.flags.writeable = False
        return self._short

    def tick_rows(self) -> list[tuple[int, int]]:
        if self._ticks is None:
            self._ticks = tick_ring_rows(self.b, STEP, short=self.short())
        return list(self._ticks)


def ring_rows(pol: np.ndarray, thr: float) -> RingRows:
    """:class:`RingRows` of the polar image ``pol`` at the threshold ``thr``.

    A polar image that cannot change (read-only, owning its data: :func:`.scale.polar`'s
    unwraps of a pass's float images, handed out again to every step that unwraps the same
    image about the same point) gets the same :class:`RingRows` each time, so that the
    ring's centre, the arc's fit and the comb's centre about one point find its rings
    once (the same values as found afresh by each)."""
    if pol.flags.writeable or pol.base is not None:
        return RingRows(pol, thr)
    key = (type(thr).__name__, float(thr))
    for im, k, got in tuple(_ROWS_MEMO):
        if im is pol and k == key:
            return got
    got = RingRows(pol, thr)
    _ROWS_MEMO.append((pol, key, got))  # (the entry holds the image: its id is not reused)
    if len(_ROWS_MEMO) > ROWS_MEMO_SIZE:
        del _ROWS_MEMO[0]
    return got


ROWS_MEMO_SIZE = 16  # as many as :data:`.scale.MEMO_SIZE` unwraps
_ROWS_MEMO: list[tuple[np.ndarray, tuple, RingRows]] = []


def fit_profile_arc(evidence: list[tuple[np.ndarray, float]], centre, face_r: float,
                    hidden_mask: np.ndarray | None, arc_start_deg: float, span_deg: float,
                    max_roll: float = MAX_ROLL_DEG) -> ArcFit:
    """Slide the profile's arc (clockwise from ``arc_start_deg``, ``span_deg`` long) round
    the dial's ring of scale marks, then let each end mark say where the arc begins or ends;
    see the module's docstring.

    ``evidence`` holds (image, threshold) pairs, one per polarity (dark marks on a light
    face, light on dark); ``hidden_mask`` the needle's pixels, which are unknown evidence."""
    fits = []
    for img, thr in evidence:
        pol, rs = polar(img if img.dtype == np.float32 else img.astype(np.float32), centre,
                        0.45 * face_r, 0.97 * face_r)
        rows_of = ring_rows(pol, thr)
        b, rings = rows_of.b, rows_of.rings()
        short, tick_rows = rows_of.short(), rows_of.tick_rows()
        # the needle's region, unwrapped over the rows of the rings below only (the rows
        # not unwrapped are never looked at)
        hidden = np.zeros_like(b)
        if hidden_mask is not None and (rings or tick_rows):
            r0 = min(lo for lo, _ in rings + tick_rows)
            r1 = max(hi for _, hi in rings + tick_rows)
            pm, _ = polar(cv2.dilate(hidden_mask, _K5).astype(np.float32), centre,
                          0.45 * face_r, 0.97 * face_r, rows=slice(r0, r1 + 1))
            hidden[r0:r1 + 1] = pm > 0.05
        for lo, hi in rings:
            rows = slice(lo, hi + 1)
            known = ~hidden[rows].any(axis=0)
            e_all = col_counts(b[rows]) / (hi + 1 - lo)  # (b is read-only: counted once)
            e = np.where(known, e_all, 0.0)
            f = _fit(e, known, arc_start_deg, span_deg, max_roll,
                     marks=(b, lo, hi, float(rs[(lo + hi) // 2])))
            fits.append(replace(f, radius=float(rs[(lo + hi) // 2]),
                                ring=(e_all, np.ones(len(e_all), bool))))
        # the ring of ticks found by their shape (short, radial strokes): where the bands
        # above miss it (numerals crossing more runs, ticks hanging from or crossing a
        # printed arc), its comb places the scale; only a comb from one is taken
        for e, known, (lo, hi) in tick_rings(b, hidden, STEP, short=short, rows=tick_rows):
            f = _fit(e, known, arc_start_deg, span_deg, max_roll, comb_only=True,
                     marks=(b, lo, hi, float(rs[(lo + hi) // 2])))
            if f.method == "comb":
                fits.append(replace(f, radius=float(rs[(lo + hi) // 2]),
                                    ring=ring_evidence(b, short, lo, hi)))
                break
    good = [f for f in fits if f.rho_deg is not None]
    if not good:
        # the first refused ring's fit, whose reason is given (and its candidate turn)
        errs = [f for f in fits if f.error]
        return errs[0] if errs else ArcFit(None, error="no scale marks found")
    good.sort(key=lambda f: (f.method != "comb", -f.ends, abs(f.mismatch_deg), -f.contrast))
    best = good[0]
    # a ring whose two end marks were both found but miss the profile's span by a tick or
    # two (a scale, shifted or cut at one end) makes the dial's marks inconsistent: a fit
    # on another ring (numerals, a band) by its end marks alone is no answer then; a comb
    # of ticks, placed by the scale's whole extent, is.  (Rings of other extent, such as
    # colour zones, miss it by far more.)  A ring that reaches beyond (or stops short of)
    # the fitted arc by as much at both ends is no contradiction: an arc band whose caps
    # pass the end ticks, numerals centred on them.  Its end marks' mean turn is the
    # fitted arc's; a scale shifted or cut at one end moves it by half the mismatch.
    for f in fits if best.method == "ends" else ():
        if f.rho_deg is None and f.ends == 2 and 0.0 < abs(f.mismatch_deg) <= NEAR_MISS_DEG \
                and not _centred_on(f, best.rho_deg):
            return ArcFit(None, error=f"scale marks at two radii disagree: {f.error}",
                          candidate_rho=best.rho_deg)
    # every other verified fit (another ring, the other polarity) must agree with it
    for f in good[1:]:
        tol = SPAN_TOL_DEG + abs(f.mismatch_deg) / 2.0 + 3.0 * (f.turn_err_deg
                                                                 + best.turn_err_deg)
        if (f.ends == 2 or f.method == "comb") and \
                abs(angle_diff(f.rho_deg, best.rho_deg)) > tol:
            return ArcFit(None, error=f"scale marks at two radii disagree on the dial's turn "
                          f"({best.rho_deg:.1f} vs {f.rho_deg:.1f} deg)",
                          candidate_rho=best.rho_deg)
    return best


_RHOS: dict[float, np.ndarray] = {}


def _centred_on(f: ArcFit, rho: float) -> bool:
    """Whether the ring of ``f``, whose two end marks miss the profile's span, is centred on
    the arc turned by ``rho``: its end marks' mean turn (``f.candidate_rho``) lies within
    half of :data:`SPAN_TOL_DEG` of ``rho``, and within a quarter of its mismatch (half of
    what one end alone, cut short or shifted, would move it)."""
    if f.candidate_rho is None:
        return False
    tol = min(SPAN_TOL_DEG / 2.0, abs(f.mismatch_deg) / 4.0)
    return abs(angle_diff(f.candidate_rho, rho)) <= tol


def _fit(e: np.ndarray, known: np.ndarray, arc_start_deg: float, span_deg: float,
         max_roll: float, comb_only: bool = False, marks=None) -> ArcFit:
    """One ring's evidence: the coarse turn that holds most of it, then the end marks.
    ``comb_only``: the caller takes only a comb's fit; without a comb the end marks are
    not looked for (the fit returned then only says there is no comb).  ``marks``: the
    thresholded polar image, the ring's rows and radius (b, lo, hi, r px), for the end
    marks' shape (:func:`.end_marks.mark_shape`)."""
    rhos = _RHOS.get(max_roll)
    if rhos is None:  # the turns tried depend on max_roll alone: made once
        rhos = _RHOS[max_roll] = np.arange(-max_roll, max_roll + 1e-9, RHO_STEP)
        rhos.flags.writeable = False
    span_cols = span_deg / STEP
    w = _window_sums(e, span_cols, (arc_start_deg + rhos) / STEP)
    i = int(w.argmax())
    # the middle of the run of turns (nearly) as good as the best: the arc's ends then sit
    # about evenly inside the gap's edges
    a, b = _run_around(w >= w[i] - PLATEAU_COLS, i)
    i = (a + b) // 2
    rho0 = float(rhos[i])
    k_in = float(_window_sums(known.astype(float), span_cols,
                              np.array([(arc_start_deg + rho0) / STEP]))[0])
    inside = float(w[i]) / max(k_in, 1.0)
    outside = (float(e.sum()) - float(w[i])) / max(float(known.sum()) - k_in, 1.0)
    contrast = inside - outside
    if inside < 0.05 or contrast < 0.5 * inside:
        return ArcFit(None, contrast=contrast,
                      error="scale marks not confined to the profile's arc", candidate_rho=rho0)
    comb = comb_turn(e, known, STEP, arc_start_deg, span_deg, rho0, max_roll)
    if comb is None and comb_only:
        return ArcFit(None, contrast=contrast, error="no comb of ticks")
    ends_fit = _ends_fit(e, known, arc_start_deg, span_deg, max_roll, rho0, contrast, marks)
    if comb is None:
        return ends_fit
    if ends_fit.rho_deg is not None and ends_fit.ends == 2 and abs(
            angle_diff(ends_fit.rho_deg, comb.rho_deg)) > SPAN_TOL_DEG + 3.0 * comb.err_deg:
        # two clean end marks and the comb disagree: neither is trusted
        return ArcFit(None, 2, ends_fit.mismatch_deg, contrast, error=(
            f"the ticks' comb and the end marks disagree on the dial's turn "
            f"({comb.rho_deg:.1f} vs {ends_fit.rho_deg:.1f} deg)"), candidate_rho=comb.rho_deg)
    return ArcFit(comb.rho_deg, comb.ends, 0.0, contrast, method="comb",
                  turn_err_deg=comb.err_deg)


def _run_around(on: np.ndarray, i: int) -> tuple[int, int]:
    """First and last index of the run of True in ``on`` (1-D, not circular) that holds
    index ``i`` (``on[i]`` True)."""
    off = (~on).nonzero()[0]
    j = int(off.searchsorted(i))
    return (int(off[j - 1]) + 1 if j > 0 else 0,
            int(off[j]) - 1 if j < len(off) else len(on) - 1)


def _ends_fit(e: np.ndarray, known: np.ndarray, arc_start_deg: float, span_deg: float,
              max_roll: float, rho0: float, contrast: float, marks=None) -> ArcFit:
    """The turn from the two end marks about the coarse turn ``rho0``."""
    cols = np.arange(len(e))
    level = mark_level(e, known, arc_start_deg + rho0, span_deg)
    if marks is not None:  # the ring's ticks' radial length, for the end marks' shape
        lengths = radial_lengths(*marks[:3])
        inside = lengths[known & (e >= level) & _in_arc(cols * STEP, arc_start_deg + rho0,
                                                          span_deg)]
        ref = percentile(inside, 90) if len(inside) else 0.0
        pb, r_lo, r_hi = marks[:3]  # (the printed arc line's rows, :mod:`.arc_line`)
        line = line_rows(pb, max(0, r_lo - MARK_MARGIN_ROWS), r_hi + 1 + MARK_MARGIN_ROWS,
                           known & _in_arc(cols * STEP, arc_start_deg + rho0, span_deg))
        marks = (*marks, lengths, ref, line)
    lo = end_mark(e, known, (arc_start_deg + rho0) / STEP, +1, level, marks)
    hi = end_mark(e, known, (arc_start_deg + rho0 + span_deg) / STEP, -1, level, marks)
    lo, hi = _behind_or_hidden(lo, hi, arc_start_deg, span_deg, rho0)
    if lo == "missing" or hi == "missing":
        one = [v[1] * STEP - a for v, a in ((lo, arc_start_deg), (hi, arc_start_deg + span_deg))
               if v not in ("missing", "hidden")]
        return ArcFit(None, contrast=contrast, error="an end mark of the scale not found "
                      "where the profile's arc puts it",
                      candidate_rho=rho0 + angle_diff(one[0], rho0) if one else rho0)
    ends = [(v[1] * STEP - a, v[0], v[2]) for v, a in ((lo, arc_start_deg),
                                                        (hi, arc_start_deg + span_deg))
            if v != "hidden"]
    if not ends:
        return ArcFit(None, contrast=contrast, error="both end marks hidden", candidate_rho=rho0)
    ests = [rho0 + angle_diff(r, rho0) for r, _, _ in ends]
    mism = ests[1] - ests[0] if len(ests) == 2 else 0.0
    # an arc's outer edge lies beyond its end mark by half a stroke, never inside it
    slack = EDGE_SLACK_DEG * sum(kind == "edge" for _, kind, _ in ends) if len(ends) == 2 \
        else 0
    if not -SPAN_TOL_DEG <= mism <= SPAN_TOL_DEG + slack:
        return ArcFit(None, 2, mism, contrast, error=f"{SPAN_MISS} {mism:+.1f} "
                      "deg off the profile's span", candidate_rho=float(np.mean(ests)))
    rho = float(np.mean(ests))
    if abs(rho) > max_roll - 2.0:
        return ArcFit(None, len(ests), mism, contrast, candidate_rho=float(np.mean(ests)),
                      error="scale marks do not fit the "
                      "profile's arc within a camera's roll")
    # an end mark placed inside a wider run of print may be off by up to half that run;
    # both off the same way turn the arc without changing its span, so the mismatch cannot
    # show it: the turn's error is up to the mean of the two ends' doubts
    unsure = float(np.mean([u for _, _, u in ends]))
    return ArcFit(rho, len(ests), mism, contrast, ends_err_deg=unsure)


def mark_level(e: np.ndarray, known: np.ndarray, start_deg: float, span_deg: float) -> float:
    """The evidence a ring's column holds to count as a mark, not gap: 0.4 of the ring's
    marks' (the 90th percentile of the known columns on the arc from ``start_deg``, clockwise
    ``span_deg`` long), and at least 0.2."""
    lit = e[known & _in_arc(np.arange(len(e)) * STEP, start_deg, span_deg)]
    return max(0.2, 0.4 * percentile(lit, 90)) if len(lit) else 1.0


def _behind_or_hidden(lo, hi, arc_start_deg: float, span_deg: float, rho0: float):
    """The two end marks of :func:`_ends_fit`, where a tick just inside the needle
    (``"behind"``, :func:`.end_marks.end_mark`) stands for its end mark only when the other
    end mark, met clear of the needle, puts the arc's turn within :data:`SPAN_TOL_DEG` of it;
    else that end is ``"hidden"``.  A tick behind the needle is the end mark, or the first
    tick inside an end mark under the needle (a needle resting on the stop pin just outside
    the minimum mark); in the second case it misses the span by a tick's pitch, so the
    span's tolerance bounds what taking it can turn the arc by, and the mismatch enters the
    reading's error bound as any two end marks' does."""
    sides = [lo, hi]
    for i, v in enumerate(sides):
        if not (isinstance(v, tuple) and v[0] == "behind"):
            continue
        other = sides[1 - i]
        ok = isinstance(other, tuple) and other[0] in ("tick", "edge")
        if ok:
            r_lo, r_hi = (rho0 + angle_diff(m[1] * STEP - a, rho0)
                          for m, a in ((lo, arc_start_deg), (hi, arc_start_deg + span_deg)))
            slack = EDGE_SLACK_DEG if other[0] == "edge" else 0.0
            ok = -SPAN_TOL_DEG <= r_hi - r_lo <= SPAN_TOL_DEG + slack
        if not ok:
            sides[i] = "hidden"
    return sides[0], sides[1]


def _in_arc(a: np.ndarray, start: float, span: float) -> np.ndarray:
    return (a - start) % 360.0 <= span
