"""Free space from the beams that came back with nothing (no return).

A beam with no return within the lidar's usable range says that the space
along it is empty as far as the sensor can see; the occupancy grid's
inverse sensor model (map_io.build_grid) otherwise learns free space only
from beams that hit something. Most mapping systems use such beams
(GMapping's ``maxUrange``, Cartographer's ``missing_data_ray_length``):
without them, an object that moved away while the robot saw its old place
only against open ground — a cart driving off 8-12 m away, a worker who
walked on from where they stood — stays in the map, since no later beam that
crosses its old cells ever ends anywhere.

A missing reading is not always open space: a dark or shiny surface, or a
random dropout, swallows single beams amid returns. So each no-return beam
is trusted only as far as its neighbours saw: its free ray ends ``margin_m``
short of the nearest range among the ``neighbours`` beams on either side (a
neighbour with no return counts as ``clear_m``; a reading too near to trust,
dust or a zero, caps it at that reading; a NaN caps it at zero). A lone
dropout amid a wall 3 m away clears no more than its neighbours' beams do,
and a beam just past a wall's end stops short of that wall's range; a run of
no-return beams (open ground) clears to ``clear_m − margin_m``.
"""

from __future__ import annotations

import math

import numpy as np


def no_return_rays(ranges_m: np.ndarray, angles_rad: np.ndarray, max_range_m: float,
                   clear_m: float | None = None, margin_m: float = 0.3,
                   neighbours: int = 1, min_ray_m: float = 0.5) -> np.ndarray:
    """End points (sensor frame, (N, 2)) of the free rays of the beams with no
    return: a reading that is +inf or at least ``max_range_m`` (the usable
    range). ``clear_m`` (default ``max_range_m``) is how far such a beam is
    taken to see; rays shorter than ``min_ray_m`` are dropped. When the beams
    cover a full turn, the first and last beams are neighbours."""
    r = np.asarray(ranges_m, float).ravel()
    a = np.asarray(angles_rad, float).ravel()
    n = len(r)
    if n == 0:
        return np.zeros((0, 2))
    clear = float(max_range_m if clear_m is None else clear_m)
    none = (r == math.inf) | (np.isfinite(r) & (r >= max_range_m))
    if not none.any():
        return np.zeros((0, 2))
    # how far each beam vouches for its neighbours: its range, clear_m when
    # it saw nothing, zero when its reading is not a number (NaN, -inf)
    reach = np.where(none, clear, np.where(np.isfinite(r), np.minimum(r, clear), 0.0))
    full_turn = n > 1 and abs(a[-1] - a[0]) * n / (n - 1) >= 2 * math.pi - 1e-6
    length = np.full(n, clear)
    for k in range(1, neighbours + 1):
        if full_turn:
            length = np.minimum(length, np.minimum(np.roll(reach, k), np.roll(reach, -k)))
        else:
            length[k:] = np.minimum(length[k:], reach[:-k])
            length[:-k] = np.minimum(length[:-k], reach[k:])
    length = length - margin_m
    keep = none & (length >= min_ray_m)
    return np.column_stack((length[keep] * np.cos(a[keep]), length[keep] * np.sin(a[keep])))
