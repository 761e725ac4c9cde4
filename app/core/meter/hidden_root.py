"""A pointer whose root the region step cannot see: its pivot from the scale ring instead.

:func:`.pointer.read_normalised` finds the pointer as the largest dark region reaching the
centre zone, and its hub as that region's thickest part there (section 3.1 of seed 000).
Some dials hide the needle's root under something light: a light hub cap (a pale hexagon
or disc over the pivot), or the ring hub of a second pointer in a colour the profile
ignores (erased to the face's grey, it cuts the needle off at the hub).  Then the region
reaching the centre zone is a cap's thin outline, a class plate or a scale arc the
needle's outer part touches, and the step refuses ("pointer hub not found", "pointer line
not found", ...), though the needle's shaft is plain to see.

Here the pivot is taken from the ring of scale marks alone
(:func:`.ring_centre.ring_centre`, about the rim's centre), the needle from its ray
evidence about that pivot (:func:`.needle.find_needle`), and the pointer's region from the
threshold image's regions that lie on the needle's line.  The needle's line must pass the
ring's centre (a needle's axis passes through its pivot): that is the check of the pivot
which the hub's circle gives otherwise.  The skeleton's axis of that region (eq. 19) stays
the second estimate of the needle, and the result goes to the profile's angles
(:mod:`.angles`), whose checks of the ring, the scale's turn, the two needle estimates and
the error bound all apply as about any hub.  There is no hub: ``hub_rms`` is left at its
"none fits" value, so nothing that trusts the hub's circle uses it.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .angles import LINE_AT_CENTRE_PX
from .dial import FACE_RADIUS
from .geometry import Line, choose_intersection, line_circle_intersections
from .needle import find_needle
from .otsu import binarize, otsu_threshold
from .pointer import CENTRE, FACE_MASK, dark_features, robust_pointer_line
from .profile import GaugeProfile
from .ring_centre import ring_centre
from .scale import ring_angle
from .thinning import zhang_suen

__all__ = ["REGION_FAILURES", "pointer_about_ring"]

# the pointer step's refusals before a hub was placed (no "centre" in its result)
REGION_FAILURES = ("pointer not found", "pointer hub not found", "pointer too short",
                   "pointer line not found")
CAP_FRAC = 0.2  # the hidden root: the centre zone's radius (of the face's), as the hub's
ON_LINE = (0.25, 0.7)  # the needle's line is sampled over these shares of the face radius
_K3 = np.ones((3, 3), np.uint8)


def pointer_about_ring(crop: np.ndarray, prof: GaugeProfile, failed: dict,
                       keypoints=None) -> dict:
    """The pointer step's result for ``crop`` (a 300 x 300 normalised crop, light face) built
    about the scale ring's centre where the region step refused (``failed``, one of
    :data:`REGION_FAILURES`); ``failed`` itself where the ring, the needle or its region is
    not found, or the needle's line misses the ring's centre.  The result carries the
    step's refusal as its ``error`` (no scale is read here) and what the profile's angles
    need: ``centre``, ``line``, ``theta``, ``pmask``, ``dark``, ``otsu_t`` and the rest.

    ``keypoints`` (a callable giving the learned keypoints on ``crop``, or None): the
    learned pivot must lie within its own tolerance (:data:`.keypoints.SPREAD_K` of its
    error scale) of the ring's centre.  The needle's line checks the pivot across the
    needle only; along it, with no hub, this is the one other estimate.  Without them,
    ``failed`` is returned.  The callable rides on in the result (``"keypoints"``)."""
    if "centre" in failed or failed.get("error") not in REGION_FAILURES or keypoints is None:
        return failed
    gray = cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY) if crop.ndim == 3 else crop
    dark = dark_features(gray)
    t = max(otsu_threshold(dark, mask=FACE_MASK), 12)
    darkf = dark.astype(np.float32)
    start = (CENTRE, CENTRE)
    for _ in range(2):
        ring = ring_centre(darkf, t, start, FACE_RADIUS, None)
        if ring is None:
            return failed
        c = (float(ring[0][0]), float(ring[0][1]))
        nf = find_needle(crop, c, 0.8 * FACE_RADIUS, needle=prof.needle,
                         ignore_colour=prof.ignore_colour, straight_rivals=True)
        if not nf.ok:
            return failed
        if math.hypot(nf.pivot_xy[0] - c[0], nf.pivot_xy[1] - c[1]) <= LINE_AT_CENTRE_PX:
            break
        # the needle's line misses the ring's centre: the ring fitted again from the
        # line's foot (the ring's fit about the rim's centre may have stayed at its start)
        start = nf.pivot_xy
    else:
        return failed
    from .keypoints import SINGLE_VIEW_GAIN, SPREAD_K, SPREAD_TO_SIGMA  # (imports the reader)

    kp = keypoints()
    if kp is None or math.hypot(kp["pivot"][0] - c[0], kp["pivot"][1] - c[1]) > \
            SPREAD_K * SPREAD_TO_SIGMA * SINGLE_VIEW_GAIN * float(kp.spread[0]):
        return failed
    u = (math.sin(math.radians(nf.angle_deg)), -math.cos(math.radians(nf.angle_deg)))
    binary = binarize(dark, t) & (FACE_MASK * np.uint8(255))
    pmask = _regions_on_line(binary, c, u)
    if pmask is None:
        return failed
    got = _axis(pmask, c, u)
    if got is None:
        return failed
    line, pts, r0 = got
    nz = cv2.findNonZero(pmask).reshape(-1, 2)
    pxs, pys = nz[:, 0].astype(float), nz[:, 1].astype(float)
    ux, uy = line.direction
    side = 1.0 if ux * u[0] + uy * u[1] >= 0 else -1.0  # the ray finder's tip side
    proj = ((pxs - c[0]) * ux + (pys - c[1]) * uy) * side
    on_axis = line.distance(np.column_stack([pxs, pys])) < 3.0
    ti = int(np.argmax(np.where(on_axis, proj, -np.inf)))
    tip = (float(pxs[ti]), float(pys[ti]))
    tip_len = float(abs(proj[ti]))
    ext_bw = float(max(0.0, np.max(np.where(on_axis, -proj, 0.0))))
    r_s = 0.8 * FACE_RADIUS
    ahead = (c[0] + u[0] * r_s, c[1] + u[1] * r_s)
    p = choose_intersection(line_circle_intersections(line, c, r_s), c, ahead)
    if p is None:
        return failed
    return {
        "error": failed["error"], "centre": c, "hub_r": r0 / 1.3, "hub_rms": 99.0,
        "line": line, "tip": tip, "tip_len": tip_len, "point": p,
        "theta": ring_angle(p[0], p[1], c), "scale": None, "scale_error": failed["error"],
        "line_centre_dist": float(line.distance(c)[0]), "n_skel": int(len(pts)),
        "tip_angle": ring_angle(tip[0], tip[1], c), "r_s": r_s, "otsu_t": t,
        "hub_from": "ring", "dark": dark, "pmask": pmask, "ext_fw": tip_len,
        "ext_bw": ext_bw, "keypoints": keypoints,
    }


def _regions_on_line(binary: np.ndarray, c, u) -> np.ndarray | None:
    """The threshold image's regions (8-connected) that the needle's line crosses between
    :data:`ON_LINE` of the face radius from the pivot, as one 0/1 mask; None if none."""
    n, labels = cv2.connectedComponents(binary, connectivity=8)
    if n < 2:
        return None
    r = np.linspace(ON_LINE[0] * FACE_RADIUS, ON_LINE[1] * FACE_RADIUS, 48)
    xs = np.clip(np.round(c[0] + u[0] * r).astype(int), 0, binary.shape[1] - 1)
    ys = np.clip(np.round(c[1] + u[1] * r).astype(int), 0, binary.shape[0] - 1)
    hit = np.unique(labels[ys, xs])
    hit = hit[hit > 0]
    if len(hit) == 0:
        return None
    return np.isin(labels, hit).astype(np.uint8)


def _axis(pmask: np.ndarray, c, u) -> tuple[Line, np.ndarray, float] | None:
    """Eq. 19 on the region's skeleton outside the centre zone (the root is hidden there),
    as :func:`.pointer.robust_pointer_line` fits it about the pivot ``c``; with the
    skeleton's points and the radius left out.  None if too few points lie on an axis."""
    r0 = CAP_FRAC * FACE_RADIUS
    for erode in (True, False):
        er = cv2.erode(pmask, _K3) if erode else pmask.copy()
        cv2.circle(er, (int(round(c[0])), int(round(c[1]))), int(r0), 0, -1)
        nz = cv2.findNonZero(zhang_suen(er))
        if nz is None:
            continue
        pts = nz.reshape(-1, 2).astype(float)
        # only the skeleton on the needle's side and near its line: a scale arc the
        # needle touches must not outweigh the shaft in the axis's seed
        v = pts - np.asarray(c, float)
        along = v @ np.asarray(u, float)
        across = np.abs(v @ np.array([-u[1], u[0]]))
        pts = pts[(along > r0) & (across < 0.1 * FACE_RADIUS + 0.1 * along)]
        if len(pts) < 8:
            continue
        line = robust_pointer_line(pts, c)
        if line is not None:
            return line, pts, r0
    return None
