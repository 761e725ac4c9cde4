"""What the learned keypoints (:mod:`.keypoints`) may settle for the angles path (:mod:`.angles`).

They are never the only estimate there: each helper compares them with a classical one
(the dial's turn from one end mark, the needle's end that is the tip, the end marks of a
pivot moved along the needle's line).
"""

from __future__ import annotations

import math

from .dial import FACE_RADIUS
from .profile import GaugeProfile
from .scale import angle_diff

__all__ = ["keypoint_turn", "learned_tip_opposes", "keypoint_tip_diff", "learned_ends_agree",
           "KP_SPAN_TOL_DEG"]

KP_SPAN_TOL_DEG = 8.0  # the learned end marks turn the dial when their arc is this close
# to the profile's span


def keypoint_turn(kp, c, prof: GaugeProfile) -> float | None:
    """The dial's turn from the learned end marks about the pivot ``c``: their bisector
    against the profile's, when their arc matches the profile's span; else None."""
    (x0, y0), (x1, y1) = kp["min_mark"], kp["max_mark"]
    a_min = math.degrees(math.atan2(x0 - c[0], -(y0 - c[1])))
    a_max = math.degrees(math.atan2(x1 - c[0], -(y1 - c[1])))
    sign = 1.0 if prof.clockwise else -1.0
    span_obs = (sign * (a_max - a_min)) % 360.0
    if abs(span_obs - prof.span_deg) > KP_SPAN_TOL_DEG:
        return None
    mid_obs = a_min + sign * span_obs / 2.0
    mid_prof = prof.min_angle_deg + sign * prof.span_deg / 2.0
    return angle_diff(mid_obs, mid_prof)


def learned_tip_opposes(keypoints, c, needle_deg: float) -> bool:
    """Whether the learned tip (``keypoints()``) points more than 90 deg from the needle's
    angle about ``c``: at its other end."""
    kp = keypoints()
    d_kp = keypoint_tip_diff(kp, c, needle_deg) if kp is not None else None
    return d_kp is not None and abs(d_kp) > 90.0


def keypoint_tip_diff(kp, c, needle_deg: float) -> float | None:
    """The learned tip's direction about ``c`` minus the needle's angle (deg)."""
    tx, ty = kp["tip"]
    if math.hypot(tx - c[0], ty - c[1]) < 0.3 * FACE_RADIUS:
        return None
    return angle_diff(math.degrees(math.atan2(tx - c[0], -(ty - c[1]))) % 360.0, needle_deg)


def learned_ends_agree(kp: dict | None, c, min_deg: float, max_deg: float,
                       tol_deg: float) -> bool:
    """Whether the learned end marks (``kp["min_mark"]``, ``kp["max_mark"]``, crop pixels)
    lie, seen from ``c``, each within ``tol_deg`` of the image angles ``min_deg`` and
    ``max_deg`` where the classical fit puts the scale's minimum and maximum marks."""
    if kp is None:
        return False
    for key, want in (("min_mark", min_deg), ("max_mark", max_deg)):
        x, y = kp[key]
        if math.hypot(x - c[0], y - c[1]) < 1.0:
            return False
        seen = math.degrees(math.atan2(x - c[0], -(y - c[1])))
        if abs(angle_diff(seen, want)) > tol_deg:
            return False
    return True
