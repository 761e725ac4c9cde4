"""A learned dial keypoint detector: the reader's fallback when its own scale finder refuses.

A small convolutional network (trained by ``bench/train_keypoints.py`` on the project's own
styled gauge generator) looks at a 128 x 128 BGR crop around the dial
and gives four heatmaps (32 x 32, stride 4): the needle's pivot, the needle's tip, and the
scale's minimum and maximum end marks.  It runs through OpenCV's dnn module from the ONNX
file in ``models/``; torch is needed only to train it.  A scale that runs counter-clockwise
(profile ``min_angle_deg > max_angle_deg``) is mirrored left-right before the network, which
was trained on clockwise scales only, and the points are mirrored back.

Each heatmap is a spatial softmax.  Its keypoint is the probability-weighted centre of the
5 x 5 cells around the peak, its *spread* the standard deviation of that window (in input
pixels), and its *peak mass* the probability inside the 3 x 3 cells at the peak (near 1
for a sure, single answer; low when the network hesitates between places).

:func:`read_keypoints` reads a gauge with them, trusting the network only as far as
independent checks agree:

0. the network looks twice: on the dial finder's crop, and again on a view made from its
   first answer (centred on the predicted pivot, the scale ring at the size it was trained
   on, turned so that the end marks' bisector sits where the profile puts it).  The two
   answers are averaged; where they disagree, a point's error scale grows by half the
   disagreement (a view the network is unsure about moves its points);
1. all four heatmaps are peaked; each end mark is then moved onto its printed tick where
   exactly one tick can be the scale's end within three of the mark's error scales
   (:mod:`.mark_snap`; the tick's error scale then replaces the network's), and with both
   marks on ticks and the dial seen head-on (its rim found round), the dial's turn below
   is the normal of the chord between them, which the pivot's error does not move (where
   no rim was found, the view's tilt is unmeasured and the turn stays the bisector's);
2. both end marks lie about as far from the pivot as each other (a scale ring), within
   what their error scales allow;
3. the arc from the minimum to the maximum mark about the pivot, in the profile's direction,
   matches the profile's span within a tolerance grown from the points' error scales;
4. the needle found classically around the predicted pivot (:func:`.needle.find_needle`,
   sub-degree) is clean and points where the predicted tip is.

The value is the needle's angle from the minimum mark, as in the calibrated reader
(:func:`.calibrated.scale_fraction`), on the dial's plane when the rim's ellipse is clear
(:mod:`.oblique`).  The end marks' orientation is taken from the network, the span from the
profile (it is knowledge, and check 3 has verified it): the two marks are set at the
profile's half-span either side of their predicted bisector, which halves the effect of a
mark's error.  The reading states an error bound (``error_bound_fs``, % of full scale):
:data:`BOUND_K` times the reading's error scale, made of the bisector's error (from the
marks' and the pivot's error scales), the refined needle's own (its centres' spread about
its axis over its length) and, on a tilted dial, the tilt correction in as much doubt as its
rim is unsupported (both as in the calibrated reader, :mod:`.calibrated`).  The confidence
falls from 1 at a bound of :data:`BOUND_GOOD` to 0 at :data:`BOUND_BAD` (0.5 where the bound
reaches 2 % FS, what the bench counts as a wrong reading), times the needle's and the tip
check's scores, so a reading that could be wrong by more than a confident one may be is
refused.  On 210 generated gauges of the seven families read by the first network (two
views, bound 2.5 error scales) no error exceeded its bound (error over bound at most 0.95);
with 3 the bound keeps a margin over that.  Any failed check is a refusal that says
which; where the end marks' spread alone (with the needle's least error) already bounds
the error too widely for a confident reading, that refusal ("marks_sure") comes before the
dial's rim and the needle are looked for, as no later check could give a reading.
"""

from __future__ import annotations

import logging
import math
import time
from pathlib import Path

import cv2
import numpy as np

from .calibrated import RIM_DOUBT
from .dial import find_dial_candidates
from .mark_snap import snap_end_mark
from .needle import angle_cw, find_needle
from .oblique import find_rectifier
from .other_dials import NEARER_UNREAD, RIVAL_READS, box_rival, nearer_unread, readings_agree
from .profile import load_profile

__all__ = ["MODEL_PATH", "KeypointFit", "load_model", "predict_keypoints", "read_keypoints",
           "FAILURES"]

log = logging.getLogger(__name__)

MODEL_PATH = Path(__file__).resolve().parent / "models" / "dial_keypoints.onnx"
IN = 128  # network input side
OUT = 32  # heatmap side
NAMES = ("pivot", "tip", "min_mark", "max_mark")
CROP_SIDE = 1.15  # crop side over the dial finder's rim diameter (whole frames)
MIN_PEAK = 0.35  # peak mass every heatmap must reach
SPAN_TOL_MIN = 3.0  # deg: the span check's tolerance never goes below this
SPREAD_K = 3.0  # the span tolerance in the points' spread (angle sigmas)
TIP_TOL_DEG = 8.0  # the refined needle vs the predicted tip direction
SPREAD_TO_SIGMA = 0.25  # a point's error per unit of its heatmap's spread (see below)
SINGLE_VIEW_GAIN = 1.5  # a point seen in one view only: its error scale grown by this
SECOND_VIEW = True  # look again, on a view centred and turned by the first answer
SIDE_PER_RING = 3.2  # the second view's side over the scale ring's radius (as in training)
BOUND_K = 3.0  # the error bound in the reading's error scales
NEEDLE_DEG = 0.3  # the refined needle's own error (deg) in the bound
BOUND_GOOD, BOUND_BAD = 1.0, 3.0  # % FS: the error bound's confidence ramp (0.5 at 2 % FS)
STOP_TOL_DEG = 5.0  # a needle this far outside an end mark reads as that end
FAILURES: dict[str, int] = {}  # model load failures by reason (counted, logged once each)

_NETS: dict[tuple, object] = {}


def _fail(reason: str) -> None:
    if reason not in FAILURES:
        log.warning("keypoint model unavailable: %s", reason)
    FAILURES[reason] = FAILURES.get(reason, 0) + 1


def load_model(path: Path | str | None = None):
    """(cv2.dnn net, None) or (None, reason); loaded once per file version."""
    p = Path(path) if path is not None else MODEL_PATH
    try:
        st = p.stat()
    except OSError:
        _fail(f"model file {p.name} missing")
        return None, f"keypoint model {p.name} missing"
    key = (str(p), st.st_mtime_ns, st.st_size)
    net = _NETS.get(key)
    if net is None:
        try:
            net = cv2.dnn.readNetFromONNX(str(p))
            net.setInput(np.zeros((1, 3, IN, IN), np.float32))
            out = net.forward()
            if out.shape != (1, len(NAMES), OUT, OUT):
                raise ValueError(f"unexpected output shape {out.shape}")
        except (cv2.error, ValueError) as e:
            _fail(f"model file {p.name} unreadable ({str(e).strip().splitlines()[-1][:80]})")
            return None, f"keypoint model {p.name} unreadable"
        _NETS.clear()
        _NETS[key] = net
    return net, None


class KeypointFit:
    """Four keypoints in input-image pixels, with their spread (px) and peak mass."""

    def __init__(self, points: np.ndarray, spread: np.ndarray, peak: np.ndarray):
        self.points, self.spread, self.peak = points, spread, peak

    def __getitem__(self, name: str) -> tuple[float, float]:
        p = self.points[NAMES.index(name)]
        return float(p[0]), float(p[1])


def _decode(logits: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(points in 128-px input coordinates, spread in input px, peak mass) per channel."""
    k = logits.shape[0]
    flat = logits.reshape(k, -1).astype(np.float64)
    prob = np.exp(flat - flat.max(1, keepdims=True))
    prob /= prob.sum(1, keepdims=True)
    prob = prob.reshape(k, OUT, OUT)
    pts, spread, peak = np.zeros((k, 2)), np.zeros(k), np.zeros(k)
    g = np.arange(OUT)
    for j in range(k):
        y, x = divmod(int(np.argmax(prob[j])), OUT)
        peak[j] = prob[j, max(0, y - 1):y + 2, max(0, x - 1):x + 2].sum()
        ys, xs = slice(max(0, y - 2), y + 3), slice(max(0, x - 2), x + 3)
        w = prob[j, ys, xs]
        # the window's columns and rows (as np.meshgrid's grids, by broadcasting)
        gx, gy = g[xs][None, :], g[ys][:, None]
        s = w.sum()
        mx, my = (w * gx).sum() / s, (w * gy).sum() / s
        var = (w * ((gx - mx) ** 2 + (gy - my) ** 2)).sum() / s
        pts[j] = ((mx + 0.5) * IN / OUT, (my + 0.5) * IN / OUT)
        spread[j] = math.sqrt(var) * IN / OUT
    return pts, spread, peak


def predict_keypoints(bgr: np.ndarray, centre, side: float, mirror: bool, net, *,
                      turn_deg: float = 0.0) -> KeypointFit:
    """The network on the square ``side`` px about ``centre``; points in ``bgr``'s pixels.

    ``turn_deg``: the view is turned anticlockwise by this much about ``centre`` before the
    network sees it (an image angle ``a``, clockwise from up, appears at ``a - turn_deg``)."""
    s = IN / side
    c, q = math.cos(math.radians(turn_deg)) * s, math.sin(math.radians(turn_deg)) * s
    m = np.array([[c, q, IN / 2 - c * centre[0] - q * centre[1]],
                  [-q, c, IN / 2 + q * centre[0] - c * centre[1]], [0, 0, 1.0]])
    if mirror:
        m = np.array([[-1, 0, IN - 1.0], [0, 1, 0], [0, 0, 1.0]]) @ m
    crop = cv2.warpAffine(bgr, m[:2], (IN, IN), flags=cv2.INTER_AREA,
                          borderMode=cv2.BORDER_REPLICATE)
    net.setInput(crop.transpose(2, 0, 1)[None].astype(np.float32))
    pts, spread, peak = _decode(net.forward()[0])
    inv = np.linalg.inv(m)
    back = pts @ inv[:2, :2].T + inv[:2, 2]
    return KeypointFit(back, spread / s, peak)


def _second_view(bgr, kp: KeypointFit, prof, net) -> KeypointFit | None:
    """The network again on a view made from its first answer: centred on the predicted
    pivot, the scale ring at the size the network was trained on, and turned so that the
    predicted end marks' bisector is where the profile puts it (the dial upright).  None
    when the first answer has no scale ring to go by."""
    (px, py), pmin, pmax = kp["pivot"], kp["min_mark"], kp["max_mark"]
    r = 0.5 * (math.hypot(pmin[0] - px, pmin[1] - py) + math.hypot(pmax[0] - px, pmax[1] - py))
    if r < 4.0:
        return None
    want = 0.5 * (prof.min_angle_deg + prof.max_angle_deg)
    seen = _bisector(angle_cw(pmin[0] - px, pmin[1] - py),
                     angle_cw(pmax[0] - px, pmax[1] - py), prof.clockwise)
    turn = (seen - want + 180.0) % 360.0 - 180.0
    return predict_keypoints(bgr, (px, py), SIDE_PER_RING * r, not prof.clockwise, net,
                             turn_deg=turn)


def _at_span(a_min: float, a_max: float, prof) -> tuple[float, float]:
    """The end marks set at the profile's half-span either side of their bisector."""
    sign = 1.0 if prof.clockwise else -1.0
    mid = _bisector(a_min, a_max, prof.clockwise)
    return mid - sign * prof.span_deg / 2.0, mid + sign * prof.span_deg / 2.0


def _bisector(a_min: float, a_max: float, clockwise: bool) -> float:
    """The angle halfway along the scale from ``a_min`` to ``a_max`` (either direction)."""
    sign = 1.0 if clockwise else -1.0
    return a_min + sign * ((sign * (a_max - a_min)) % 360.0) / 2.0


def _combine(a: KeypointFit, b: KeypointFit | None) -> tuple[KeypointFit, np.ndarray]:
    """Two views' keypoints averaged (weights: inverse squared spread) and each point's
    error scale in px: its spread in :data:`SPREAD_TO_SIGMA` units, grown by half the
    two views' disagreement (a point the views do not agree on is not known better)."""
    if b is None:
        return a, a.spread * SPREAD_TO_SIGMA * SINGLE_VIEW_GAIN
    wa, wb = 1.0 / np.maximum(a.spread, 0.5) ** 2, 1.0 / np.maximum(b.spread, 0.5) ** 2
    pts = (a.points * wa[:, None] + b.points * wb[:, None]) / (wa + wb)[:, None]
    spread = 1.0 / np.sqrt(wa + wb)
    gap = np.hypot(*(a.points - b.points).T)
    sigma = np.hypot(spread * SPREAD_TO_SIGMA, gap / 2.0)
    return KeypointFit(pts, spread, np.minimum(a.peak, b.peak)), sigma


BOX_MIN_FILL = 0.22  # the dial finder's smallest rim, as a share of the image's side


def _boxes(gray: np.ndarray, known=None) -> list[tuple[tuple[float, float], float]]:
    """Squares to look in: the whole image for a crop, the dial finder's rims otherwise.
    ``known``: (image, min_fill, candidates) of a dial search already made (the classical
    reader's, :func:`.search.full_search`); used when it searched this very image alike."""
    h, w = gray.shape[:2]
    if abs(h - w) <= 0.12 * max(h, w):
        return [((w / 2.0, h / 2.0), float(max(h, w)))]
    if known is not None and known[1] == BOX_MIN_FILL and known[0].shape == gray.shape \
            and np.array_equal(known[0], gray):
        cands = list(known[2])
    else:
        cands = find_dial_candidates(gray, min_fill=BOX_MIN_FILL)
    out = []
    for e in cands[:2]:
        out.append(((e.cx, e.cy), CROP_SIDE * max(e.width, e.height)))
    return out


def _ramp(x: float, bad: float, good: float) -> float:
    return float(min(1.0, max(0.0, (x - bad) / (good - bad))))


def read_keypoints(image: np.ndarray, prof, *, min_confidence: float = 0.5,
                   model_path: Path | str | None = None, t0: float | None = None,
                   dial_candidates=None):
    """Read ``image`` (BGR or grey) with the keypoint network and the checks above.

    Returns a :class:`.reader.Reading` with ``method="keypoints"``; a refusal names the
    check that failed.  Never raises for bad image content or a bad model file.
    ``dial_candidates``: a dial search the caller already made (see :func:`_boxes`)."""
    from .calibrated import scale_fraction
    from .reader import Reading

    t0 = time.perf_counter() if t0 is None else t0
    prof = load_profile(prof)
    unit = prof.unit

    def refuse(reason, **kw):
        return Reading(value=None, unit=unit, confidence=0.0, error=reason, method="keypoints",
                       elapsed_ms=round((time.perf_counter() - t0) * 1000.0, 3), **kw)

    net, why = load_model(model_path)
    if net is None:
        return refuse(why)
    bgr = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR) if image.ndim == 2 else image
    gray = cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)
    boxes = _boxes(gray, dial_candidates)
    if not boxes:
        return refuse("dial not found")
    last, got, unread = None, None, []
    for centre, side in boxes:
        if got is not None and not box_rival(got[1], (centre, side), CROP_SIDE, gray.shape):
            continue  # the dial read again (its bezel, its face), or one off the aim
        r = _read_box(bgr, gray, prof, centre, side, net, scale_fraction, min_confidence)
        if r[0] is None:
            last = last or r
            unread.append((centre, side))
        elif got is None and nearer_unread((centre, side), unread, CROP_SIDE, gray.shape):
            return refuse(NEARER_UNREAD.format(why=last[1]), raw_value=r[0]["raw_value"],
                          error_bound_fs=r[0]["error_bound_fs"], scores=r[0]["scores"])
        elif got is None:
            got = (r[0], (centre, side))
        elif not readings_agree(got[0], r[0], prof.full_scale):
            return refuse(RIVAL_READS.format(v=r[0]["value"]), raw_value=got[0]["raw_value"],
                          error_bound_fs=got[0]["error_bound_fs"],
                          scores=dict(got[0]["scores"],
                                      rival_dial_value=round(float(r[0]["value"]), 6)))
    if got is not None:
        return Reading(**got[0], unit=unit, method="keypoints",
                       elapsed_ms=round((time.perf_counter() - t0) * 1000.0, 3))
    return refuse(last[1], **last[2])


def _least_bound_fs(sig_turn: float, span_deg: float) -> float:
    """A lower bound on :func:`_read_box`'s error bound (% FS) from the dial's turn's least
    error scale (deg; from the end marks alone): the same sums with the needle's error at
    its least (:data:`NEEDLE_DEG`) and no tilt's doubt; the span a hair wider than the
    profile's, which the reading's own (the marks set at the profile's half-span) may
    differ from by a rounding."""
    sig_deg = math.hypot(sig_turn, NEEDLE_DEG)
    return BOUND_K * (100.0 * sig_deg / (span_deg * (1.0 + 1e-9)))


def _turn_sigma(sig: np.ndarray, r_min: float, r_max: float, span_deg: float | None) -> float:
    """The error scale (deg) of the end marks' bisector about the pivot: half of each
    mark's own error across its radius, and the pivot's error as it turns the bisector.

    A pivot moved by ``d`` turns the marks' angles by ``-d . t_i / r`` (``t_i`` the ring's
    tangent at mark ``i``); their mean, the bisector, by ``-d . (t_1 + t_2) / 2r``, where
    ``(t_1 + t_2) / 2`` is ``cos(span / 2)`` times the tangent at the bisector.  So only
    the pivot's error across the bisector counts, by ``|cos(span / 2)|``: none on a 180 deg
    scale (both marks and the pivot on one line, whose direction no slide of the pivot
    along or across it changes), 0.71 on a 90 or 270 deg one.  This holds on the dial's
    plane; ``span_deg=None`` (the rim not seen, so the view's tilt is unmeasured) counts the
    pivot's error in each mark's angle as if apart (0.71 at every span), whose margin on a
    180 deg scale covers the angles an unseen tilt bends."""
    r = 0.5 * (r_min + r_max)
    if span_deg is None:
        return math.degrees(math.hypot(math.hypot(sig[2], sig[0]) / max(r_min, 1.0),
                                       math.hypot(sig[3], sig[0]) / max(r_max, 1.0)) / 2.0)
    marks = math.hypot(sig[2] / max(r_min, 1.0), sig[3] / max(r_max, 1.0)) / 2.0
    pivot = abs(math.cos(math.radians(span_deg / 2.0))) * sig[0] / max(r, 1.0)
    return math.degrees(math.hypot(marks, pivot))


def _chord_sigma(pmin, pmax, sig: np.ndarray) -> float:
    """The error scale (deg) of the chord's normal between the two end marks, from their
    own error scales (px) over the chord's length."""
    chord = math.hypot(pmax[0] - pmin[0], pmax[1] - pmin[1])
    return math.degrees(math.hypot(sig[2], sig[3]) / max(chord, 1.0))


def _chord_bisector(pmin, pmax, near: float) -> float:
    """The scale's bisector (image angle, clockwise from up) as the normal of the chord
    from the minimum to the maximum mark: of its two directions, the one nearer ``near``
    (the bisector about the pivot).  The end marks lie symmetric about the bisector, so
    the chord between them is square to it wherever the pivot is along it."""
    cx, cy = pmax[0] - pmin[0], pmax[1] - pmin[1]
    a = angle_cw(cy, -cx)
    b = (a + 180.0) % 360.0
    return a if abs((a - near + 180.0) % 360.0 - 180.0) <= 90.0 else b


def _snap_marks(gray, kp: KeypointFit, sig: np.ndarray, prof) -> int:
    """Each end mark moved onto its printed tick where :func:`.mark_snap.snap_end_mark` finds
    exactly one in the mark's uncertainty region (its error scale then the tick's); the
    strips the needle may lie in (the predicted tip's direction within its doubt, and the
    tail's for a two-ended needle) are not searched.  ``kp`` and ``sig`` are updated in
    place; returns how many marks moved."""
    (px, py), (tx, ty) = kp["pivot"], kp["tip"]
    tip_deg = angle_cw(tx - px, ty - py)
    doubt = max(TIP_TOL_DEG, SPREAD_K * math.degrees(
        math.hypot(sig[1], sig[0]) / max(math.hypot(tx - px, ty - py), 1.0)))
    dirs = (tip_deg, tip_deg + 180.0) if prof.needle == "two-ended" else (tip_deg,)
    sign = 1.0 if prof.clockwise else -1.0
    moved = 0
    gray = np.asarray(gray, np.float32)  # as each strip samples it, converted once
    for j, outward in ((2, -sign), (3, sign)):
        got = snap_end_mark(gray, (px, py), kp.points[j], float(sig[j]), outward, dirs, doubt)
        if got is not None:
            kp.points[j], sig[j] = got[0], got[1]
            moved += 1
    return moved


def _read_box(bgr, gray, prof, centre, side, net, scale_fraction, min_confidence):
    """(reading fields or None, refusal reason, geometry) for one crop box."""
    first = predict_keypoints(bgr, centre, side, not prof.clockwise, net)
    second = _second_view(bgr, first, prof, net) if SECOND_VIEW else None
    kp, sig = _combine(first, second)
    scores = {f"peak_{n}": round(float(p), 4) for n, p in zip(NAMES, kp.peak, strict=True)}
    geo: dict = {"scores": scores, "dial_centre_xy": kp["pivot"],
                 "scale_ends_xy": (kp["min_mark"], kp["max_mark"])}
    worst = int(np.argmin(kp.peak))
    if kp.peak[worst] < MIN_PEAK:
        return None, f"keypoints unsure ({NAMES[worst]} heatmap not peaked)", geo
    snapped = _snap_marks(gray, kp, sig, prof)
    if snapped:
        scores["marks_on_ticks"] = float(snapped)  # not a check: how many marks were moved
    (px, py), pmin, pmax = kp["pivot"], kp["min_mark"], kp["max_mark"]
    r_min, r_max = math.hypot(pmin[0] - px, pmin[1] - py), math.hypot(pmax[0] - px, pmax[1] - py)
    if min(r_min, r_max) < 0.15 * side or \
            abs(r_min - r_max) > 0.3 * max(r_min, r_max) + SPREAD_K * math.hypot(sig[2], sig[3]):
        return None, "keypoints: end marks not on one scale ring about the pivot", geo
    radius = 0.5 * (r_min + r_max)
    geo["dial_radius_px"] = radius
    # the marks' own error scales (deg about the pivot), for the span check and the bound
    sig_min = math.degrees(math.hypot(sig[2], sig[0]) / r_min)
    sig_max = math.degrees(math.hypot(sig[3], sig[0]) / r_max)
    # the error bound below is at least what the marks' spread and the needle's least error
    # make of it (the tilt's doubt and a wider needle only add): where that alone keeps the
    # confidence under the minimum, no check below can give a reading, and the dial's rim
    # and the needle are not looked for
    # the dial's turn: the marks' bisector about the pivot, whose error is half the marks'
    # combined (:func:`_turn_sigma`); with both marks on their ticks and the dial seen
    # head-on, the normal of the chord between them, which the pivot's error does not move
    sig_turn = _turn_sigma(sig, r_min, r_max, prof.span_deg)
    sig_chord = _chord_sigma(pmin, pmax, sig) if snapped == 2 else None
    least = sig_turn if sig_chord is None else min(sig_turn, sig_chord)
    most_sure = round(_ramp(_least_bound_fs(least, prof.span_deg), BOUND_BAD, BOUND_GOOD), 4)
    if most_sure < min_confidence:
        scores["marks_sure"] = most_sure  # at most this
        return None, "low confidence (keypoints: marks_sure)", geo
    rect = find_rectifier(gray, (px, py), radius, bgr)
    if not rect.rim_seen:
        # no rim: the view's tilt is unmeasured, and the pivot counts as in each mark apart
        sig_turn = _turn_sigma(sig, r_min, r_max, None)
    if rect.ellipse is not None:
        (ex, ey), (ew, eh), ea = rect.ellipse
        geo["dial_ellipse"] = (float(ex), float(ey), float(ew), float(eh), float(ea))
    # check 3: the span about the pivot, against the profile's, within the points' errors
    a_min = rect.angle(pmin[0] - px, pmin[1] - py)
    a_max = rect.angle(pmax[0] - px, pmax[1] - py)
    sign = 1.0 if prof.clockwise else -1.0
    span_obs = (sign * (a_max - a_min)) % 360.0
    tol = max(SPAN_TOL_MIN, SPREAD_K * math.hypot(sig_min, sig_max))
    scores["span_diff_deg"] = round(span_obs - prof.span_deg, 2)
    if abs(span_obs - prof.span_deg) > tol:
        return None, (f"keypoints: scale arc ({span_obs:.0f} deg) does not match the profile's "
                      f"span ({prof.span_deg:.0f} deg)"), geo
    # the marks at the profile's half-span either side of their bisector (on the dial plane);
    # the chord's normal only on a rim seen round (a rim not found may hide a tilt, which
    # bends the chord's normal off the bisector unseen: a hard frame read 1.7 % FS off at
    # a bound of 1.0 so)
    if sig_chord is not None and rect.identity and rect.rim_seen:
        mid = _chord_bisector(pmin, pmax, _bisector(a_min, a_max, prof.clockwise))
        a_min, a_max = mid - sign * prof.span_deg / 2.0, mid + sign * prof.span_deg / 2.0
        sig_turn = sig_chord
        scores["turn_from_chord"] = 1.0  # not a check: the turn taken from the chord
    else:
        a_min, a_max = _at_span(a_min, a_max, prof)

    def on_scale(a: float) -> bool:
        f, span = scale_fraction(a_min % 360.0, a_max % 360.0, rect.angle(
            math.sin(math.radians(a)), -math.cos(math.radians(a))), prof.clockwise)
        return -STOP_TOL_DEG / span <= f <= 1.0 + STOP_TOL_DEG / span

    nf = find_needle(bgr, (px, py), radius, needle=prof.needle,
                     ignore_colour=prof.ignore_colour, on_scale=on_scale,
                     straight_rivals=True)
    scores.update({k: round(v, 4) for k, v in nf.scores.items()})
    if not nf.ok:
        return None, f"keypoints: {nf.error}", geo
    geo["pointer_tip_xy"] = nf.tip_xy
    geo["pointer_line_xy"] = (nf.pivot_xy, nf.tip_xy)
    # check 4: the refined needle points where the network's tip is
    tx, ty = kp["tip"]
    qx, qy = nf.pivot_xy
    a_tip = angle_cw(tx - qx, ty - qy)
    d_tip = abs((a_tip - nf.angle_deg + 180.0) % 360.0 - 180.0)
    tip_tol = max(TIP_TOL_DEG, SPREAD_K * math.degrees(
        math.hypot(sig[1], sig[0]) / max(math.hypot(tx - qx, ty - qy), 1.0)))
    scores["tip_agrees"] = round(_ramp(d_tip, tip_tol, 0.5 * tip_tol), 4)
    if d_tip > tip_tol:
        return None, f"keypoints: needle ({nf.angle_deg:.0f} deg) and predicted tip " \
                     f"({a_tip:.0f} deg) disagree", geo
    t = math.radians(nf.angle_deg)
    a_needle = rect.angle(math.sin(t), -math.cos(t))
    frac, span = scale_fraction(a_min % 360.0, a_max % 360.0, a_needle, prof.clockwise)
    # the error bound: the dial's turn rests on the two marks' bisector, whose error is half
    # the marks' combined error; the needle's own (its centres' spread about its axis over
    # its length, as in the calibrated reader); and a tilt correction in doubt by as much as
    # its rim is unsupported (:data:`.calibrated.RIM_DOUBT`).  BOUND_K of those together.
    sig_needle = max(NEEDLE_DEG, math.degrees(max(nf.rms_px, 0.3) / max(nf.length_px, 1.0)))
    sig_deg = math.hypot(sig_turn, sig_needle)
    sig_rect = 0.0
    if not rect.identity:
        i_min, i_max = _at_span(angle_cw(pmin[0] - px, pmin[1] - py),
                                angle_cw(pmax[0] - px, pmax[1] - py), prof)
        f_img, _ = scale_fraction(i_min % 360.0, i_max % 360.0, nf.angle_deg, prof.clockwise)
        sig_rect = 100.0 * abs(frac - f_img) * min(1.0, RIM_DOUBT * (1.0 - rect.support))
    bound_fs = BOUND_K * math.hypot(100.0 * sig_deg / span, sig_rect)
    # a needle beyond an end mark reads that end: only the doubt reaching inside counts
    bound_fs = max(bound_fs - 100.0 * max(-frac, frac - 1.0, 0.0),
                   BOUND_K * 100.0 * NEEDLE_DEG / span)
    scores["marks_sure"] = round(_ramp(bound_fs, BOUND_BAD, BOUND_GOOD), 4)
    tol_f = STOP_TOL_DEG / span
    if frac < -tol_f or frac > 1.0 + tol_f:
        below = frac < 0
        deg = (-frac if below else frac - 1.0) * span
        return None, (f"pointer outside the scale ({deg:.0f} deg "
                      f"{'below the minimum' if below else 'beyond the maximum'})"), geo
    frac = min(max(frac, 0.0), 1.0)
    raw = prof.value_at_fraction(frac)
    checks = {k: v for k, v in scores.items()
              if not k.startswith(("peak_", "span_diff", "marks_on_ticks", "turn_from"))}
    conf = float(np.prod(list(checks.values())))
    geo["scores"] = scores
    if conf < min_confidence:
        worst = min(checks, key=checks.get)
        return None, f"low confidence (keypoints: {worst})", geo
    band = prof.in_normal_band(raw)
    return dict(value=float(raw), confidence=round(conf, 4), raw_value=float(raw),
                angle_deg=prof.min_angle_deg + frac * (prof.max_angle_deg - prof.min_angle_deg),
                in_normal_band=band, error_bound_fs=round(bound_fs, 4), **geo), None, geo
