"""A made-up room's scans for the mapper's tests."""

import numpy as np

from app.core.localisation.se2 import relative


def room_points(pose, rng, n=360):
    """A 12 m × 8 m room's walls seen from ``pose`` (in its frame), lightly noisy."""
    corners = [(-2.0, -4.0), (10.0, -4.0), (10.0, 4.0), (-2.0, 4.0), (-2.0, -4.0)]
    pts = []
    for (x1, y1), (x2, y2) in zip(corners[:-1], corners[1:], strict=True):
        t = np.linspace(0, 1, n // 4, endpoint=False)
        pts.append(np.column_stack((x1 + t * (x2 - x1), y1 + t * (y2 - y1))))
    world = np.vstack(pts) + rng.normal(0, 0.003, (n, 2))
    return np.array([relative(pose, (x, y, 0.0))[:2] for x, y in world])
