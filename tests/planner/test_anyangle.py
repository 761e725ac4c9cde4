import numpy as np

from app.core.planner import astar
from app.core.planner.anyangle import (
    line_of_sight,
    polyline_length,
    shorten,
    smooth_curve,
    turning_points,
)


def test_line_of_sight_respects_corners():
    b = np.zeros((5, 5), bool)
    assert line_of_sight(b, (0, 0), (4, 4))
    b[1, 2] = True
    b[2, 1] = True
    assert not line_of_sight(b, (0, 0), (4, 4)), "cannot squeeze between diagonal blocks"
    b2 = np.zeros((5, 5), bool)
    b2[2, 2] = True
    assert not line_of_sight(b2, (0, 1), (4, 3))
    assert line_of_sight(b2, (0, 0), (0, 4))


def test_shorten_reduces_turns_and_length_and_keeps_sight(rng):
    b = rng.random((60, 60)) < 0.12
    b[0, 0] = b[59, 59] = False
    r = astar(b, (0, 0), (59, 59))
    assert r.found
    verts = shorten(b, r.cells)
    assert verts[0] == (0, 0) and verts[-1] == (59, 59)
    assert turning_points(verts) < turning_points(r.cells)
    assert polyline_length(verts) <= r.length + 1e-9
    for a, c in zip(verts, verts[1:], strict=False):
        assert line_of_sight(b, a, c)


def test_smooth_curve_stays_on_free_cells():
    b = np.zeros((30, 30), bool)
    b[5:25, 14:16] = True
    r = astar(b, (15, 2), (15, 28))
    verts = shorten(b, r.cells)
    curve = smooth_curve(b, verts, step=0.25)
    rc = np.floor(curve + 0.5).astype(int)
    assert not b[rc[:, 0], rc[:, 1]].any()
    assert np.allclose(curve[0], verts[0]) and np.allclose(curve[-1], verts[-1])
    # Smoother than the polyline: no sharp heading jump between samples.
    d = np.diff(curve, axis=0)
    ang = np.arctan2(d[:, 0], d[:, 1])
    jump = np.abs((np.diff(ang) + np.pi) % (2 * np.pi) - np.pi)
    assert jump.max() < np.radians(45)


def test_turning_points_counts_changes_only():
    assert turning_points([(0, 0), (0, 1), (0, 2), (1, 3), (2, 4), (2, 5)]) == 2
    assert turning_points([(0, 0), (5, 5)]) == 0
