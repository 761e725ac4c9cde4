"""A thin wall seen from both sides: the two faces are different surfaces
(icp.stacked_reference's ``faces``; the mapping mode's loop closures)."""

import math

import numpy as np

from app.core.localisation.icp import IcpConfig, icp, scan_normals, stacked_reference
from app.core.localisation.se2 import relative

# a room 8 m × 6 m with a wall 0.3 m thick across its middle, open at x ∈ (-0.5, 0.5)
THICK = 0.3
SEGMENTS = [((-4, -3), (4, -3)), ((4, -3), (4, 3)), ((4, 3), (-4, 3)), ((-4, 3), (-4, -3)),
            ((-3.5, THICK / 2), (-0.5, THICK / 2)), ((-3.5, -THICK / 2), (-0.5, -THICK / 2)),
            ((0.5, THICK / 2), (3.5, THICK / 2)), ((0.5, -THICK / 2), (3.5, -THICK / 2))]


def _scan(pose, beams=360, max_range_m=3.2):
    """Points (sensor frame) where the beams from ``pose`` meet the nearest segment;
    beams longer than ``max_range_m`` return nothing (so neither scan sees
    the room's far wall beyond the thin one)."""
    x, y, th = pose
    out = []
    for a in np.linspace(-math.pi, math.pi, beams, endpoint=False):
        d = np.array([math.cos(th + a), math.sin(th + a)])
        best = math.inf
        for (ax, ay), (bx, by) in SEGMENTS:
            e = np.array([bx - ax, by - ay])
            m = np.array([[d[0], -e[0]], [d[1], -e[1]]])
            if abs(np.linalg.det(m)) < 1e-12:
                continue
            t, u = np.linalg.solve(m, np.array([ax - x, ay - y]))
            if t > 0 and 0 <= u <= 1:
                best = min(best, t)
        if best < max_range_m:
            out.append((best * math.cos(a), best * math.sin(a)))
    return np.array(out)


def _reference(faces: bool):
    """Keyframes along the wall's north side, at their true poses."""
    cfg = IcpConfig()
    scans = []
    for x in (-2.0, -1.0, 0.0, 1.0, 2.0):
        pose = np.array([x, 1.2, 0.0])
        pts = _scan(pose)
        scans.append((pose, pts, *scan_normals(pts, cfg.normal_neighbours)))
    return stacked_reference(scans, cfg.normal_neighbours, cfg.bucket_m, faces=faces)


def test_a_scan_from_the_far_side_of_a_thin_wall_is_not_pulled_across_it():
    here = np.array([0.3, -1.1, math.radians(5)])  # south of the wall: sees its other face
    pts = _scan(here)
    faced = icp(pts, _reference(faces=True), here)
    err = relative(here, faced.pose)
    assert math.hypot(err[0], err[1]) < 0.05 and abs(err[2]) < math.radians(0.5)
    # without the faces the wall's two sides are paired: the fit moves across it
    blind = icp(pts, _reference(faces=False), here)
    assert abs(blind.pose[1] - here[1]) > 0.15


def test_faces_point_towards_the_scans_own_sensor():
    ref = _reference(faces=True)
    x = np.abs(ref.points[:, 0])
    on_wall = (np.abs(ref.points[:, 1] - THICK / 2) < 0.02) & (x > 0.7) & (x < 3.3)
    assert on_wall.sum() > 50
    facing = ref.facing[on_wall & ref.planar]
    assert np.all(facing[:, 1] > 0.99)  # the north face, seen from the north
