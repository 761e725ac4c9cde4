"""Weld seams and the shell's edges in the climber's downward camera frame:
the straight lines a crawler on a tank wall fixes its position on (seed 003
§3 uses the seams as the wall's landmarks; the geometry of the fix is
:meth:`.wall_ekf.WallEkf.seam_seen`'s).

From one grey frame (rows against the body's forward axis, columns against
its left, ``m_per_px`` metres a pixel):

1. edges: Gaussian smoothing, then Canny with thresholds from the frame's own
   gradient distribution (a dull plate and a glaring one alike);
2. straight lines: the standard Hough transform (OpenCV), a line needing
   votes from ``MIN_SUPPORT`` of the frame's width;
3. lines of one direction (within ``SAME_DIR_RAD``) and ``MERGE_PX`` apart are
   one edge; each edge's polarity is read off the frame across it (the mean
   grey 3–8 px either side along its whole visible length);
4. a weld bead is an edge followed, ``BEAD_MIN_M``–``BEAD_MAX_M`` further on,
   by one of the other polarity (the bead brighter than the plate under a ring
   light, or darker under a low one): its axis is midway; an edge no
   bead claims, with a step of ``EDGE_STEP`` grey levels or more over a
   quarter of the frame, is the shell's edge (the plate ends there) and is
   its own line.

:func:`lines_to_sightings` turns the lines, seen in the body frame, into the
EKF's sightings with the robot's own heading estimate: horizontal or vertical
on the wall, the direction in the image, and the offset from the image centre
along the wall's y (a girth seam) or x (a vertical one). A line neither near
horizontal nor near vertical on the estimate is no shell line and is left out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

MIN_SUPPORT = 0.45  # Hough votes, as a share of the frame's width
SAME_DIR_RAD = math.radians(4.0)
MERGE_PX = 3.0
BEAD_MIN_M, BEAD_MAX_M = 0.006, 0.035
EDGE_STEP = 40.0  # grey levels across a lone edge (the shell's end)
BEAD_STEP = 12.0  # across each side of a bead
AXIS_TOL_RAD = math.radians(20.0)  # how far from horizontal or vertical a shell line may seem


@dataclass(frozen=True)
class LineSeen:
    """A line in the body frame: its direction ``angle_rad`` from the forward
    axis towards the left (modulo π), the foot of the perpendicular from the
    image centre (``fwd_m``, ``left_m``), and what it is ("bead" or "edge")."""

    angle_rad: float
    fwd_m: float
    left_m: float
    kind: str


def grey(img) -> np.ndarray:
    """The frame as one grey channel (a camera's BGR frame converted)."""
    img = np.asarray(img)
    return cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) if img.ndim == 3 else img


def edge_map(img: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Canny's edges of the smoothed grey frame, with thresholds from the frame's
    own gradient distribution, and the smoothed frame's gradients (gx, gy); the
    seams' and the rims' (:mod:`.rim_camera`) first step."""
    g = cv2.GaussianBlur(img, (0, 0), 1.5)
    gx = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3)
    mag = cv2.magnitude(gx, gy)
    hi = max(60.0, float(np.percentile(mag, 97)))
    return cv2.Canny(g, 0.4 * hi, hi, L2gradient=True), gx, gy


def _side_means(img: np.ndarray, xx: np.ndarray, yy: np.ndarray, rho: float,
                phi: float) -> tuple[float, float]:
    """Mean grey 3–8 px on the − and + side of the line x cos φ + y sin φ = ρ
    (``xx``, ``yy``: the pixels' coordinates)."""
    d = xx * math.cos(phi) + yy * math.sin(phi) - rho
    minus = (d <= -3) & (d >= -8)
    plus = (d >= 3) & (d <= 8)
    if minus.sum() < 20 or plus.sum() < 20:
        return math.nan, math.nan
    return float(img[minus].mean()), float(img[plus].mean())


def find_lines(img: np.ndarray, m_per_px: float) -> list[LineSeen]:
    """The weld beads' axes and the shell's edges in one grey frame."""
    img = grey(img)
    h, w = img.shape
    edges = edge_map(img)[0]
    raw = cv2.HoughLines(edges, 1, math.pi / 360, int(MIN_SUPPORT * min(h, w)))
    if raw is None:
        return []
    # one edge per direction and place: the strongest (first) line of each cluster
    kept: list[tuple[float, float]] = []
    for rho, phi in raw[:, 0, :]:
        rho, phi = float(rho), float(phi)
        dup = False
        for r2, p2 in kept:
            dp = abs(phi - p2)
            if dp < SAME_DIR_RAD and abs(rho - r2) <= MERGE_PX:
                dup = True
            elif abs(dp - math.pi) < SAME_DIR_RAD and abs(rho + r2) <= MERGE_PX:
                dup = True
            if dup:
                break
        if not dup:
            kept.append((rho, phi))
        if len(kept) >= 24:
            break
    # directions: group the edges, each as (signed offset along a common normal, polarity)
    groups: list[list[tuple[float, float, float]]] = []
    ref: list[float] = []
    for rho, phi in kept:
        for k, p0 in enumerate(ref):
            dp = (phi - p0 + math.pi / 2) % math.pi - math.pi / 2
            if abs(dp) < SAME_DIR_RAD:
                if abs(phi - p0) > math.pi / 2:  # the same line with its normal flipped
                    rho, phi = -rho, phi - math.copysign(math.pi, phi - p0)
                groups[k].append((rho, phi, 0.0))
                break
        else:
            ref.append(phi)
            groups.append([(rho, phi, 0.0)])
    out: list[LineSeen] = []
    cx, cy = (w - 1) / 2, (h - 1) / 2
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    for group in groups:
        lines = []
        for rho, phi, _ in group:
            lo, hi = _side_means(img, xx, yy, rho, phi)
            if math.isfinite(lo):
                lines.append((rho, phi, hi - lo))  # > 0: brighter on the + side (rising)
        lines.sort()
        used = set()
        for i, (ra, pa, sa) in enumerate(lines):
            if i in used or abs(sa) < BEAD_STEP:
                continue
            for j in range(i + 1, len(lines)):
                rb, pb, sb = lines[j]
                gap = (rb - ra) * m_per_px
                if gap > BEAD_MAX_M:
                    break
                if j not in used and gap >= BEAD_MIN_M and sb * sa < 0 and abs(sb) >= BEAD_STEP:
                    used.update((i, j))
                    out.append(_to_body((ra + rb) / 2, (pa + pb) / 2, cx, cy, m_per_px, "bead"))
                    break
        for i, (ra, pa, sa) in enumerate(lines):
            if i not in used and abs(sa) >= EDGE_STEP:
                out.append(_to_body(ra, pa, cx, cy, m_per_px, "edge"))
    return out


def _to_body(rho: float, phi: float, cx: float, cy: float, m: float, kind: str) -> LineSeen:
    """Hough's x cos φ + y sin φ = ρ (pixels, origin top left) in the body frame."""
    c, s = math.cos(phi), math.sin(phi)
    rc = rho - (cx * c + cy * s)
    u, v = rc * c, rc * s  # the foot of the perpendicular from the centre: right, down
    angle = math.atan2(s, -c) % math.pi  # the line's direction (−sin φ, cos φ) in (u, v)
    return LineSeen(angle, -v * m, -u * m, kind)


def lines_to_sightings(lines: list[LineSeen], theta: float
                       ) -> list[tuple[bool, float, float]]:
    """The lines as the wall EKF's sightings, on the heading estimate ``theta``:
    ``(horizontal, direction in the image relative to the heading, offset from
    the image centre along the wall's y for a horizontal line, x for a vertical
    one)`` (:meth:`.wall_ekf.WallEkf.seam_seen`)."""
    out = []
    c, s = math.cos(theta), math.sin(theta)
    for ln in lines:
        phi = (theta + ln.angle_rad) % math.pi  # the line's direction on the wall
        fx = ln.fwd_m * c - ln.left_m * s
        fy = ln.fwd_m * s + ln.left_m * c
        if min(phi, math.pi - phi) <= AXIS_TOL_RAD:
            out.append((True, ln.angle_rad, fy - fx * math.tan(phi)))
        elif abs(phi - math.pi / 2) <= AXIS_TOL_RAD:
            out.append((False, ln.angle_rad, fx - fy / math.tan(phi)))
    return out
