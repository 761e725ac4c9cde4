"""The face-aware submap grid (face_grid.py): a scan of one face of a thin
wall stays on that face, where the plain grid fit snaps it onto the wall's
other face, seen by a keyframe from the next room."""

import math

import numpy as np

from app.core.localisation.face_grid import join_facing
from app.core.localisation.submap_match import Submap, SubmapConfig, match_submap

# two rooms 6 m wide, parted by a wall 0.15 m thick between y = 0 and y = 0.15
WALLS = [((-3.0, 0.0), (3.0, 0.0)), ((-3.0, -4.0), (-3.0, 0.0)), ((3.0, -4.0), (3.0, 0.0)),
         ((-3.0, -4.0), (3.0, -4.0)),
         ((-3.0, 0.15), (3.0, 0.15)), ((-3.0, 0.15), (-3.0, 4.15)), ((3.0, 0.15), (3.0, 4.15)),
         ((-3.0, 4.15), (3.0, 4.15))]


def _scan(pose, beams=181, fov=math.pi):
    """Ray-cast points (sensor frame, beam order) of a 180° lidar at ``pose``."""
    x, y, th = pose
    out = []
    for b in np.linspace(-fov / 2, fov / 2, beams):
        dx, dy = math.cos(th + b), math.sin(th + b)
        best = math.inf
        for (ax, ay), (bx, by) in WALLS:
            ex, ey = bx - ax, by - ay
            den = dx * ey - dy * ex
            if abs(den) < 1e-12:
                continue
            t = ((ax - x) * ey - (ay - y) * ex) / den  # along the ray
            u = ((ax - x) * dy - (ay - y) * dx) / den  # along the wall
            if t > 1e-6 and -1e-9 <= u <= 1 + 1e-9:
                best = min(best, t)
        if best < 30:
            out.append((best * math.cos(b), best * math.sin(b)))
    return np.array(out)


def _fit(face_bins):
    cfg = SubmapConfig(face_bins=face_bins)
    below, above = (0.0, -2.0, math.pi / 2), (0.2, 2.2, -math.pi / 2)
    sub = Submap([(np.array(below), _scan(below)), (np.array(above), _scan(above))], cfg)
    true = np.array([0.4, -1.5, math.pi / 2])
    guess = true + np.array([0.0, 0.1, 0.0])  # nearer the far face (0.05) than its own (0.1)
    return match_submap(_scan(true), sub, guess).pose - true


def test_plain_grid_fit_takes_the_far_face():
    err = _fit(0)
    assert err[1] > 0.1  # a wall's thickness (0.15 m) off: the premise of the test


def test_face_aware_fit_stays_on_its_face():
    err = _fit(12)
    assert abs(err[1]) < 0.02 and abs(err[2]) < math.radians(0.5)


def test_facing_points_towards_the_sensor():
    pts = join_facing(_scan((0.0, -2.0, math.pi / 2)), 0.5, 0.05)
    ahead = (pts[:, 0] > 1.9) & (np.abs(pts[:, 1]) < 2.0)  # the thin wall, 2 m ahead
    assert ahead.sum() > 20
    assert np.all(pts[ahead, 2] < -0.95)  # back towards the sensor (−x of its frame)


def test_mapping_config_layers_only_the_grids_asked():
    from app.core.localisation.mapping_config import MappingConfig

    cfg = MappingConfig(face_grid="ties")
    assert cfg.grid_cfg("final").face_bins == 12 and cfg.grid_cfg("ties").face_bins == 12
    assert cfg.grid_cfg("local").face_bins == 0 and cfg.grid_cfg("closure").face_bins == 0
    assert MappingConfig().grid_cfg("final").face_bins == 0
