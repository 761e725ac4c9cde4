"""Finding the scale itself: its tick marks and its end marks, around the dial centre.

Beyond the paper: a gauge turned in its mounting or a rolled camera moves the whole scale;
reading the pointer against the detected end marks, not against the image's vertical,
cancels that rotation.  Works on the polar unwrapping of the dark-feature image.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .counts import col_counts, row_counts

__all__ = ["ARC_MISMATCH", "ScaleFit", "find_scale"]

N_ANG = 720  # 0.5 deg per column
_TH = np.arange(N_ANG) * (360.0 / N_ANG)
_SIN = np.sin(np.radians(_TH)).astype(np.float32)
_COS = np.cos(np.radians(_TH)).astype(np.float32)
_K5 = np.ones((5, 5), np.uint8)
ARC_MISMATCH = "scale arc"  # how the refusal starts where the ticks span another arc
POINTER_HALF_DEG = 3.0  # a pointer's line hides ticks this far either side (and half a step)


@dataclass(frozen=True)
class ScaleFit:
    """Detected scale: clockwise angles (deg, image frame) of the arc's two end marks."""

    start_deg: float  # first tick clockwise after the gap
    end_deg: float  # last tick before the gap (start + span, span > 0)
    step_deg: float  # spacing of adjacent ticks
    n_ticks: int  # ticks detected
    residual_deg: float  # rms of the uniform-spacing fit
    radius: float  # radius of the tick ring
    extended: int = 0  # end ticks restored because the pointer hid them


def polar(img: np.ndarray, centre, r0: float, r1: float,
          rows: slice | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Rows = radii r0..r1 (1 px), columns = clockwise angle from up, 0.5 deg apart.

    ``rows`` (optional) unwraps only those rows of that image (each pixel is sampled on its
    own, so they are the same values), with all the radii still returned.

    An image that cannot change (read-only, owning its data: the float images made once
    per pass by :func:`.ring_centre.pass_images`) is unwrapped once per centre and rows:
    the few steps that unwrap it about the same point get the same (read-only) array."""
    memo = None
    if not img.flags.writeable and img.base is None:
        # (the centre as the float32 the unwrap uses: two starts that converge to within
        # its rounding unwrap alike)
        memo = (id(img), np.float32(centre[0]), np.float32(centre[1]), float(r0), float(r1),
                None if rows is None else (rows.start, rows.stop, rows.step))
        for im, k, got in tuple(_MEMO):
            if k == memo and im is img:
                return got
    key = (float(r0), float(r1))
    cached = _POLAR_OFFSETS.get(key)
    if cached is None:  # the ring offsets depend only on the radii: computed once
        rs = np.arange(r0, r1, 1.0, dtype=np.float32)
        cached = _POLAR_OFFSETS[key] = (rs, rs[:, None] * _SIN[None, :],
                                        rs[:, None] * _COS[None, :])
    rs, ox, oy = cached
    if rows is not None:
        ox, oy = ox[rows], oy[rows]
    mx = np.float32(centre[0]) + ox
    my = np.float32(centre[1]) - oy
    pol = cv2.remap(img, mx, my, cv2.INTER_LINEAR, borderValue=0)
    if memo is not None:  # (the entry holds the image, so its id is not reused meanwhile)
        pol.flags.writeable = False
        _MEMO.append((img, memo, (pol, rs)))
        if len(_MEMO) > MEMO_SIZE:
            del _MEMO[0]
    return pol, rs


_POLAR_OFFSETS: dict[tuple[float, float], tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
MEMO_SIZE = 16  # unwraps of unchanging images kept (the newest; ≤ 0.2 MB each)
_MEMO: list[tuple[np.ndarray, tuple, tuple[np.ndarray, np.ndarray]]] = []


def _runs_circular(on: np.ndarray) -> list[tuple[int, int]]:
    """(start, length) of True runs in a circular boolean array."""
    starts, lens = _run_arrays(on)
    return list(zip(starts.tolist(), lens.tolist(), strict=True))


def _run_arrays(on: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Starts and lengths of the True runs of a circular boolean array, as two arrays
    (empty when it is all True or all False); a run across the end counts once."""
    n = len(on)
    off = (~on).nonzero()[0]
    if len(off) == 0 or len(off) == n:
        return np.zeros(0, np.intp), np.zeros(0, np.intp)
    shift = int(off[0])
    r = np.empty(n + 2, np.int8)
    r[0] = r[-1] = 0
    r[1:n + 1 - shift], r[n + 1 - shift:-1] = on[shift:], on[:shift]  # np.roll(on, -shift)
    d = np.diff(r)
    starts = (d == 1).nonzero()[0]
    lens = (d == -1).nonzero()[0] - starts
    return (starts + shift) % n, lens


def _lsq_line(x: np.ndarray, y: np.ndarray) -> tuple[float, float] | None:
    """Least squares y = a + b x in closed form (about the means); None when all x are
    equal."""
    xm, ym = float(x.mean()), float(y.mean())
    dx = x - xm
    sxx = float(dx @ dx)
    if sxx <= 0.0:
        return None
    b = float(dx @ (y - ym)) / sxx
    return ym - b * xm, b


def find_scale(
    dark: np.ndarray,
    thr: float,
    centre,
    face_r: float,
    pointer_mask: np.ndarray | None,
    pointer_angle: float | None,
    span_deg: float,
    model_deg: np.ndarray | None = None,
) -> tuple[ScaleFit | None, str | None]:
    """Tick ring, its tick angles and the two end marks; (fit, None) or (None, reason).

    ``dark`` is the background-flattened darkness image and ``thr`` its Otsu threshold.  The
    pointer is masked out first.  The tick ring is the band of radii where a ring crosses
    most dark runs; tick centres are fitted with uniform spacing (robust to a few lost
    ticks), and an end mark hidden under the pointer is restored using the profile's span.
    """
    if pointer_mask is not None:
        # (0 under the grown mask: ``dark`` kept where the mask is 0, by a mask of 255s)
        keep = cv2.compare(cv2.dilate(pointer_mask, _K5), 0, cv2.CMP_EQ)
        img = cv2.bitwise_and(dark, keep).astype(np.float32)
    else:
        img = dark.astype(np.float32)
    pol, rs = polar(img, centre, 0.45 * face_r, 0.97 * face_r)
    b = pol > thr
    runs = row_counts(b[:, 1:] != b[:, :-1]) / 2.0  # edges crossed per ring
    # a ring must be crossed by many runs on three neighbouring radii (not one noisy edge)
    # (each ring's two neighbours, circular: np.roll(runs, 1) and np.roll(runs, -1))
    runs = np.minimum(np.minimum(runs, np.concatenate((runs[-1:], runs[:-1]))),
                      np.concatenate((runs[1:], runs[:1])))
    runs[0] = runs[-1] = 0
    if runs.max() < 6:
        return None, "no tick marks found"
    band = runs >= 0.7 * runs.max()
    # keep the contiguous band around the row with most runs
    top = int(runs.argmax())
    lo = top
    while lo > 0 and band[lo - 1]:
        lo -= 1
    hi = top
    while hi < len(band) - 1 and band[hi + 1]:
        hi += 1
    bands = [(lo, hi)]
    # second try: the rows just inside, crossed by the longer (major) ticks only, for when
    # blur has merged the minor ticks
    hi2 = lo - 1
    while hi2 > 0 and runs[hi2] < 6:
        hi2 -= 1
    lo2 = hi2
    while lo2 > 0 and runs[lo2 - 1] >= 6 and runs[lo2 - 1] >= 0.6 * runs[hi2]:
        lo2 -= 1
    if hi2 - lo2 >= 2 and lo - hi2 < 6:
        bands.append((lo2, hi2))
    best, why0 = None, "no tick marks found"
    for lo, hi in bands:
        fit, why = _fit_band(pol, rs, b, thr, lo, hi, pointer_angle, span_deg, model_deg)
        if fit is None:
            why0 = why if best is None else why0
            continue
        if best is None or fit.residual_deg / fit.step_deg < best.residual_deg / best.step_deg:
            best = fit
        if best.residual_deg / best.step_deg < 0.1:
            break
    return (best, None) if best is not None else (None, why0)


def _fit_band(pol, rs, b, thr, lo, hi, pointer_angle, span_deg, model_deg):
    prof = np.maximum(pol[lo:hi + 1] - thr, 0).mean(axis=0)  # (np.clip(., 0, None))
    on = col_counts(b[lo:hi + 1]) / (hi + 1 - lo) >= 0.5
    starts, lens = _run_arrays(on)
    if len(starts) < 6:
        return None, "too few tick marks"
    # darkness-weighted centre of every run at once: position within its run, weight
    first = np.cumsum(lens) - lens
    pos = np.arange(int(lens.sum())) - np.repeat(first, lens)
    wts = prof[(np.repeat(starts, lens) + pos) % N_ANG] + 1e-6
    cents = ((starts + np.add.reduceat(pos * wts, first) / np.add.reduceat(wts, first))
             * (360.0 / N_ANG)) % 360.0
    order = np.argsort(cents)
    cents = cents[order]
    gaps = np.diff(np.concatenate([cents, [cents[0] + 360.0]]))
    g = int(gaps.argmax())
    # ticks in clockwise order starting after the largest gap, unwrapped past 360 deg (every
    # other gap is smaller than the largest, so the only wrap is where the sequence restarts)
    seq = np.concatenate([cents[g + 1:], cents[:g + 1] + 360.0]) if g + 1 < len(cents) \
        else cents
    # ticks next to the pointer may be half hidden: they count, but do not steer the fit
    if pointer_angle is not None:
        near_ptr = np.abs((seq - pointer_angle + 180.0) % 360.0 - 180.0) < 4.5
    else:
        near_ptr = np.zeros(len(seq), bool)
    if model_deg is not None:
        fit = _fit_model(seq, np.asarray(model_deg, float), near_ptr)
        if fit is None:
            return None, "tick marks do not match the profile's tick table"
        start, end, step, n_used, rms = fit
        rr = float(rs[(lo + hi) // 2])
        return ScaleFit(start % 360.0, start % 360.0 + (end - start), step, n_used, rms, rr), None
    d = np.diff(seq)
    step = float(np.sort(d)[(len(d) - 1) // 2:len(d) // 2 + 1].mean())  # median
    if step <= 0.3:
        return None, "tick marks not resolved"
    k = np.round((seq - seq[0]) / step)
    keep = ~near_ptr
    if keep.sum() < 6:
        return None, "too few tick marks"
    a = b_ = 0.0
    good = keep
    for _ in range(3):
        ab = _lsq_line(k[keep], seq[keep])  # phi_k = a + b k, uniform spacing
        if ab is None:
            return None, "tick spacing is irregular"
        a, b_ = ab
        res = seq - (a + b_ * k)
        good = np.abs(res) < 0.3 * step
        new = good & ~near_ptr
        if new.sum() < 6 or (new == keep).all():
            keep = new if new.sum() >= 6 else keep
            break
        keep = new
    kk = k[keep]
    if len(kk) < 6:
        return None, "tick spacing is irregular"
    rms = float(np.sqrt(np.mean((seq[keep] - (a + b_ * kk)) ** 2)))
    k0, k1 = float(k[good | keep].min()), float(k[good | keep].max())
    start, end = a + b_ * k0, a + b_ * k1
    step = float(b_)
    extended = 0
    missing = (span_deg - (end - start)) / step
    m_int = int(round(missing))
    if abs(span_deg - (end - start)) < min(0.02 * span_deg, 0.5 * step):
        m_int = 0  # within 2 %: residual distortion, not a lost tick (scored by the reader)
    elif abs(missing - m_int) > 0.35:
        return None, (f"{ARC_MISMATCH} ({end - start:.0f} deg) does not match the profile's "
                      f"span ({span_deg:.0f} deg)")
    if m_int != 0:
        if m_int < 0 or m_int > 2 or pointer_angle is None:
            return None, (f"{ARC_MISMATCH} ({end - start:.0f} deg) does not match the "
                          f"profile's span ({span_deg:.0f} deg)")
        # the ticks restored must lie under the pointer: one of them within half a step (and
        # the pointer's own half-width) of its line.  A pointer a tick or two inside the
        # found end hides no end tick; the lost one is elsewhere (under a colour zone, print)
        pa = pointer_angle % 360.0
        reach = 0.5 * step + POINTER_HALF_DEG
        js = np.arange(1, m_int + 1)
        at_start = np.abs((start - js * step - pa + 180.0) % 360.0 - 180.0).min() <= reach
        at_end = np.abs((end + js * step - pa + 180.0) % 360.0 - 180.0).min() <= reach
        if at_start and not at_end:
            start -= m_int * step
        elif at_end and not at_start:
            end += m_int * step
        else:
            return None, "an end mark of the scale is hidden"
        extended = m_int
    rr = float(rs[(lo + hi) // 2])
    return ScaleFit(start % 360.0, start % 360.0 + (end - start), step, int(keep.sum()), rms, rr,
                    extended), None


def angle_diff(a: float, b: float) -> float:
    """a - b wrapped to (-180, 180]."""
    return (a - b + 180.0) % 360.0 - 180.0


def ring_angle(x: float, y: float, centre) -> float:
    return math.degrees(math.atan2(x - centre[0], -(y - centre[1]))) % 360.0


def _fit_model(seq: np.ndarray, model: np.ndarray, near_ptr: np.ndarray):
    """Match detected tick angles to a tick table: phi = rho + s * model (least squares).

    Tries aligning the table's first tick with the first detected tick and its last with the
    last detected; keeps the alignment that explains most ticks.  Returns
    (start, end, step, n_matched, rms) or None.
    """
    step = float(np.median(np.diff(model)))
    best = None
    for rho0 in (seq[0] - model[0], seq[-1] - model[-1]):
        rho, sc, cand = rho0, 1.0, None
        for _ in range(3):
            pred = rho + sc * model
            near = np.abs(seq[:, None] - pred[None, :]).argmin(axis=1)
            res = seq - pred[near]
            ok = (np.abs(res) < 0.35 * step * sc) & ~near_ptr
            if ok.sum() < 6:
                break
            fit = _lsq_line(model[near[ok]], seq[ok])  # phi = rho + s * model
            if fit is None:
                cand = None
                break
            rho, sc = fit
            if not 0.9 < sc < 1.1:  # noqa: SIM108
                cand = None
                break
            rms = float(np.sqrt(np.mean((seq[ok] - rho - sc * model[near[ok]]) ** 2)))
            cand = (rho + sc * model[0], rho + sc * model[-1], step * sc, int(ok.sum()), rms)
        if cand is not None and (best is None or (cand[3], -cand[4]) > (best[3], -best[4])):
            best = cand
    return best
