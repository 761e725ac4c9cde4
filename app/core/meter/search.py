"""Step 0: where the dial is.  Rim candidates, a rim refitted around the hub, and the
affine pass that normalises a rim to the 300 x 300 crop of :mod:`.pointer`."""

from __future__ import annotations

import math

import cv2
import numpy as np

from .dial import (
    FACE_RADIUS,
    NORM_SIZE,
    RIM_SURE,
    DialEllipse,
    face_radius,
    find_dial_candidates,
    off_centre,
    rectify,
)
from .other_dials import distinct
from .pointer import CENTRE as _C
from .pointer import read_normalised
from .profile import GaugeProfile
from .rim import is_head_on_crop, rim_points_around

__all__ = ["SAME_VIEW_PX", "affine_pass", "ellipse_in_input", "full_search", "hub_consistent",
           "read_vote_rims", "rim_pass", "view_shift_px", "vote_rims"]

_IDENTITY_2X3 = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


def hub_consistent(res: dict) -> bool:
    """The hub lies where the rim says the dial's centre is (within 10 px of 300)."""
    return "centre" in res and math.hypot(res["centre"][0] - _C, res["centre"][1] - _C) <= 10


SAME_VIEW_PX = 0.5  # two crops whose pixels sample the image within this of each other: one view
_CROP_PTS = np.array([[0.0, 0.0, 1.0], [NORM_SIZE, 0.0, 1.0], [0.0, NORM_SIZE, 1.0],
                      [NORM_SIZE, NORM_SIZE, 1.0], [NORM_SIZE / 2.0, NORM_SIZE / 2.0, 1.0]]).T


def view_shift_px(m_a: np.ndarray, m_b: np.ndarray) -> float:
    """How far apart (crop px) two image -> normalised crop affine maps (2 x 3) put the
    image points that ``m_a`` puts at the crop's corners and centre: the most the two crops'
    contents are shifted against each other (an affine map's difference over the square
    is largest at a corner)."""
    a = np.vstack([m_a, [0.0, 0.0, 1.0]])
    b = np.vstack([m_b, [0.0, 0.0, 1.0]])
    q = b @ np.linalg.solve(a, _CROP_PTS)
    return float(np.abs(q[:2] / q[2] - _CROP_PTS[:2]).max())


def full_search(base: np.ndarray, crop_like: bool, prof: GaugeProfile,
                found: dict | None = None, seen=None):
    """Step 0 in full: up to three rim candidates, then a rim refitted around the hub.

    Returns (ellipse, normalised crop, affine map, radius, results) or None (no dial).
    ``found`` (optional): the rim candidates are left in it, as ``"dial_candidates"``:
    (the image searched, ``min_fill``, the candidates), for a later step that would search
    the same image alike (the keypoint fallback's boxes).  ``seen`` (optional): a pass
    already made on this image, as that tuple (the crop fast path's); a rim whose crop
    samples the image within :data:`SAME_VIEW_PX` of that one's is that view, resampled:
    its pass is not made again, and ``seen`` itself stands for it (the caller, finding it
    returned, knows the view was read already)."""
    min_fill = 0.5 if crop_like else 0.22
    cands = find_dial_candidates(base, min_fill=min_fill)
    if found is not None:
        found["dial_candidates"] = (base, min_fill, tuple(cands))
    if not cands:
        if not crop_like:
            return None
        bh, bw = base.shape[:2]
        cands = [DialEllipse(bw / 2.0, bh / 2.0, 0.9 * bw, 0.9 * bh, 0.0, 0.0)]
    first = None
    for ell in cands[:3]:
        cur = _pass_or_seen(base, ell, prof, seen)
        first = first or cur
        if hub_consistent(cur[4]):
            return cur  # the hub is where this rim says the centre is: a consistent dial
    cur = first
    re = _rim_around_hub(base, first)
    if re is not None:
        again = _pass_or_seen(base, re, prof, seen)
        if hub_consistent(again[4]):
            cur = again
    return cur


def _pass_or_seen(base: np.ndarray, ell: DialEllipse, prof: GaugeProfile, seen):
    """:func:`rim_pass` on ``ell``, or ``seen`` (a pass already made, as that tuple) where
    the two crops are one view (:func:`view_shift_px` within :data:`SAME_VIEW_PX`)."""
    norm, m_aff, r_aff = affine_pass(base, ell)
    if seen is not None and view_shift_px(seen[2], m_aff) <= SAME_VIEW_PX:
        return seen
    return ell, norm, m_aff, r_aff, read_normalised(norm, prof)


VOTE_RIMS = 2  # rims of the circle vote tried where the contours' rims held no dial


def vote_rims(found: dict, chosen: DialEllipse) -> list[DialEllipse]:
    """Rims of the gradients' circle vote (:func:`.dial.find_dial_candidates` with
    ``votes_only``) that are none of the first rims the search tried (``found``: what
    :func:`full_search` left) and lie on more edge than the rim it chose (``chosen``), the
    best :data:`VOTE_RIMS` of them, one about each centre.

    A backdrop's long straight edges (a grating, bricks, pipes, cladding) can fill the
    longest contours, so that the dial's rim is not among the search's candidates; straight
    edges do not feed the circle vote.  None where the rim chosen lies on edges over
    :data:`.dial.RIM_SURE` of its perimeter (a rim so plain is the dial's, and the vote
    is not cast).  Only rims about another centre (:func:`.other_dials.distinct`; one about
    the same centre is the chosen dial's bezel, face or printed arc, which the search has
    read), on more edge than the rim chosen and not farther from the frame's centre (the
    camera is aimed at the dial it reads, :mod:`.other_dials`)."""
    base, min_fill, cands = found["dial_candidates"]
    if chosen.support >= RIM_SURE:
        return []
    tried = list(cands[:3])
    aim = off_centre(chosen.cx, chosen.cy, base.shape)
    out = []
    for ell in find_dial_candidates(base, min_fill=min_fill, votes_only=True):
        if ell.support <= chosen.support or any(_same_rim(ell, e) for e in tried):
            continue
        if off_centre(ell.cx, ell.cy, base.shape) > aim or \
                not all(distinct(ell, e) for e in (chosen, *out)):
            continue  # (one rim about each centre, the best supported)
        out.append(ell)
        if len(out) == VOTE_RIMS:
            break
    return out


def read_vote_rims(found: dict, chosen: DialEllipse, read_at):
    """The first reading (by ``read_at(rim)``) about a rim of :func:`vote_rims` that gives a
    value, or None; where none does, the best vote rim is put first among the search's
    candidates in ``found``, so that the learned keypoints look there first."""
    votes = vote_rims(found, chosen)
    for ell in votes:
        got = read_at(ell)
        if got.value is not None:
            return got
    if votes:
        im, fill, cands = found["dial_candidates"]
        found["dial_candidates"] = (im, fill, (votes[0], *cands))
    return None


def _same_rim(a: DialEllipse, b: DialEllipse) -> bool:
    """Two rim ellipses that would give much the same crop (centres within 5 % of their
    size, sizes within 10 %)."""
    size = 0.25 * (a.width + a.height + b.width + b.height)
    return (math.hypot(a.cx - b.cx, a.cy - b.cy) < 0.05 * size
            and abs(a.width + a.height - b.width - b.height) < 0.2 * size)


def rim_pass(base: np.ndarray, ell: DialEllipse, prof: GaugeProfile):
    """The first pass on one rim: (ellipse, normalised crop, affine map, radius, results)."""
    norm, m_aff, r_aff = affine_pass(base, ell)
    return ell, norm, m_aff, r_aff, read_normalised(norm, prof)


def _rim_around_hub(base: np.ndarray, first) -> DialEllipse | None:
    """Re-fit the rim from rays cast out of the hub found in a first, inconsistent pass."""
    ell, norm, m_aff, _, res = first
    if "centre" not in res:
        return None
    pts = rim_points_around(_gray(norm), res["centre"])
    if len(pts) < 40:
        return None
    e = cv2.fitEllipse(pts)
    for _ in range(2):  # drop rays that hit a numeral, the pointer or glare
        (cx, cy), (w, h), ang = e
        t = math.radians(ang)
        dx, dy = pts[:, 0] - cx, pts[:, 1] - cy
        xr = dx * math.cos(t) + dy * math.sin(t)
        yr = -dx * math.sin(t) + dy * math.cos(t)
        res_px = np.abs(np.hypot(xr / (w / 2), yr / (h / 2)) - 1.0) * (w + h) / 4
        keep = res_px < 2.0
        if keep.sum() < 30:
            return None
        pts = pts[keep]
        e = cv2.fitEllipse(pts)
    inv = cv2.invertAffineTransform(m_aff)
    back = cv2.transform(pts.reshape(-1, 1, 2), inv).reshape(-1, 2)
    (cx, cy), (w, h), ang = cv2.fitEllipse(back.astype(np.float32))
    return DialEllipse(cx, cy, w, h, ang, ell.support)


def affine_pass(base: np.ndarray, ell: DialEllipse, face_edge: bool = False):
    """Affine rectification of the rim ellipse, rescaled so the face edge lands at 135 px.

    ``face_edge``: the ellipse was fitted to the face edge itself (the crop fast path), so
    the face already lands at 135 px and is not measured again; if that rim already is the
    normalised circle (:func:`is_head_on_crop`), the crop is used as it is, without a warp."""
    if face_edge and is_head_on_crop(ell, base.shape):
        return base, _IDENTITY_2X3, FACE_RADIUS
    norm, m_aff = rectify(base, ell)
    if face_edge:
        return norm, m_aff, FACE_RADIUS
    fr = face_radius(_gray(norm))
    r_aff = FACE_RADIUS
    if fr is not None and abs(fr - FACE_RADIUS) > 0.03 * FACE_RADIUS and \
            0.6 * FACE_RADIUS < fr < 1.12 * FACE_RADIUS:
        r_aff = FACE_RADIUS * FACE_RADIUS / fr
        norm, m_aff = rectify(base, ell, radius_out=r_aff)
    return norm, m_aff, r_aff



def _gray(img: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) if img.ndim == 3 else img



def ellipse_in_input(ell: DialEllipse, to_base: np.ndarray):
    sx, sy = to_base[0, 0], to_base[1, 1]
    if abs(sx - sy) < 1e-9:
        return (ell.cx / sx, ell.cy / sy, ell.width / sx, ell.height / sy, ell.angle_deg)
    # anisotropic resize of a near-square crop: refit from sampled rim points
    t = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    a, b = ell.width / 2, ell.height / 2
    ca, sa = math.cos(math.radians(ell.angle_deg)), math.sin(math.radians(ell.angle_deg))
    x = ell.cx + a * np.cos(t) * ca - b * np.sin(t) * sa
    y = ell.cy + a * np.cos(t) * sa + b * np.sin(t) * ca
    pts = np.column_stack([x / sx, y / sy]).astype(np.float32)
    (cx, cy), (w, h), ang = cv2.fitEllipse(pts)
    return (float(cx), float(cy), float(w), float(h), float(ang))


