"""Drawn 2-D worlds for synthetic laser logs (bench/synth_carmen.py): a grid
map made into a smooth wall field, a 2-D lidar ray-cast in it, and a tour
through it that revisits places, sampled into scans as a thinned log is.

- ``World``: a blocked grid (cells of ``cell_m``) up-sampled to 5 cm and
  blurred (σ 0.35 cell), its 0.5 level being the walls: a map's staircase of
  cells becomes a wall with rounded corners, read between samples by
  bilinear interpolation. The map's border is walled.
- ``World.cast``: every beam marched in 2.5 cm steps to the first sample
  inside a wall, then bisected on the interpolated field to 0.1 mm.
- ``tour``: waypoints spread by farthest-point sampling over the free space
  the robot fits in (``clearance_m`` from every wall), visited in
  nearest-neighbour order and then in the reverse order, legs planned with
  the project's A* (app/core/planner/astar.py) on a 0.1 m grid, each leg
  smoothed; the robot turns on the spot where the path reverses.
- ``sample_scans``: a pose wherever the robot has gone ``step_m`` (drawn per
  scan, ±15 %) or turned ``turn_max_deg`` since the last one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from app.core.planner.astar import astar

FIELD_M = 0.05  # the wall field's sample spacing
PLAN_M = 0.1  # the planning grid's cell


@dataclass
class World:
    """Walls as the 0.5 level of a blurred field; x along columns, y along
    rows (row 0 at y = 0, the map's last line: y points up)."""

    field: np.ndarray  # (rows, cols) in [0, 1], 1 = inside a wall
    res: float = FIELD_M
    clearance: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        free = self.field < 0.5
        self.clearance = ndimage.distance_transform_edt(free) * self.res

    @property
    def size_m(self) -> tuple[float, float]:
        return self.field.shape[1] * self.res, self.field.shape[0] * self.res

    def value(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The field at world points, bilinear between the samples (at cell
        centres); outside the grid: inside a wall."""
        u = np.asarray(x) / self.res - 0.5
        v = np.asarray(y) / self.res - 0.5
        h, w = self.field.shape
        c0 = np.floor(u).astype(np.int64)
        r0 = np.floor(v).astype(np.int64)
        fu, fv = u - c0, v - r0
        out = (c0 < 0) | (r0 < 0) | (c0 >= w - 1) | (r0 >= h - 1)
        c0 = np.clip(c0, 0, w - 2)
        r0 = np.clip(r0, 0, h - 2)
        f = self.field
        val = ((f[r0, c0] * (1 - fu) + f[r0, c0 + 1] * fu) * (1 - fv)
               + (f[r0 + 1, c0] * (1 - fu) + f[r0 + 1, c0 + 1] * fu) * fv)
        return np.where(out, 1.0, val)

    def clearance_at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        c = np.clip((np.asarray(x) / self.res).astype(np.int64), 0, self.field.shape[1] - 1)
        r = np.clip((np.asarray(y) / self.res).astype(np.int64), 0, self.field.shape[0] - 1)
        return self.clearance[r, c]

    def cast(self, pose, angles: np.ndarray, max_range_m: float) -> np.ndarray:
        """True range of each beam (bearing ``angles`` in the sensor frame at
        ``pose``); ``inf`` where no wall lies within ``max_range_m``."""
        x, y, th = (float(v) for v in pose)
        a = th + np.asarray(angles, float)
        ca, sa = np.cos(a)[:, None], np.sin(a)[:, None]
        h = self.res / 2
        n = len(a)
        hit = np.zeros(n, bool)
        lo, hi = np.zeros(n), np.zeros(n)
        block = 64  # samples marched at once, only for the beams still in the open
        for start in range(0, int(max_range_m / h) + 2, block):
            act = np.where(~hit)[0]
            if not len(act):
                break
            t = (start + np.arange(1, block + 1)) * h
            inside = self.value(x + ca[act] * t, y + sa[act] * t) >= 0.5
            got = inside.any(axis=1)
            k = np.argmax(inside, axis=1)
            idx = act[got]
            hi[idx] = t[k[got]]
            lo[idx] = t[k[got]] - h
            hit[idx] = True
        c1, s1 = ca[:, 0], sa[:, 0]
        for _ in range(8):  # bisection of the step that entered the wall
            mid = (lo + hi) / 2
            wall = self.value(x + c1 * mid, y + s1 * mid) >= 0.5
            hi = np.where(wall, mid, hi)
            lo = np.where(wall, lo, mid)
        r = (lo + hi) / 2
        return np.where(hit & (r <= max_range_m), r, np.inf)


def world_from_blocked(blocked: np.ndarray, cell_m: float, flip: bool = True) -> World:
    """A World of a blocked grid (row 0 = the map's first line, drawn at the
    top when ``flip``), cells of ``cell_m`` (a multiple of 5 cm), walled
    round its border."""
    k = int(round(cell_m / FIELD_M))
    if k < 1 or abs(k * FIELD_M - cell_m) > 1e-9:
        raise ValueError(f"cell size {cell_m} m is not a multiple of {FIELD_M} m")
    b = np.pad(np.asarray(blocked, bool), 1, constant_values=True)
    if flip:
        b = b[::-1]
    up = np.kron(b.astype(np.float32), np.ones((k, k), np.float32))
    f = ndimage.gaussian_filter(up, sigma=0.35 * k, mode="nearest") if k > 1 else up
    return World(np.asarray(f, float))


def widen_doors(blocked: np.ndarray, width_cells: int) -> np.ndarray:
    """Open every gap of a one-cell-thick wall line (a door of the Moving AI
    room maps) to ``width_cells`` along the wall."""
    b = np.asarray(blocked, bool).copy()
    h, w = b.shape
    half = width_cells // 2
    for axis in (0, 1):
        g = b if axis == 0 else b.T
        for r in np.where(g.mean(axis=1) > 0.5)[0]:
            line = g[r]
            for c in np.where(~line)[0]:
                lo, hi = max(c - half, 1), min(c - half + width_cells, line.size - 1)
                g[r, lo:hi] = False
        if axis == 1:
            b = g.T.copy()
    return b


# ---- the tour ----------------------------------------------------------------------


def _plan_grid(world: World, clearance_m: float) -> tuple[np.ndarray, int]:
    k = int(round(PLAN_M / world.res))
    h, w = (s // k for s in world.clearance.shape)
    c = world.clearance[:h * k, :w * k].reshape(h, k, w, k).min(axis=(1, 3))
    return c < clearance_m, k


def _largest_component(free: np.ndarray) -> np.ndarray:
    lab, n = ndimage.label(free)
    if n == 0:
        raise ValueError("no free space wide enough for the robot")
    sizes = ndimage.sum(free, lab, index=np.arange(1, n + 1))
    return lab == 1 + int(np.argmax(sizes))


def _farthest_points(cells: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    pick = [int(rng.integers(len(cells)))]
    d = np.hypot(*(cells - cells[pick[0]]).T)
    for _ in range(n - 1):
        pick.append(int(np.argmax(d)))
        d = np.minimum(d, np.hypot(*(cells - cells[pick[-1]]).T))
    return cells[pick]


def _smooth(xy: np.ndarray, world: World, min_clear_m: float, half_m: float = 0.5) -> np.ndarray:
    """Resample a polyline at 5 cm and average it over ±``half_m``, keeping
    the raw point wherever the average comes nearer a wall than
    ``min_clear_m``."""
    seg = np.hypot(*np.diff(xy, axis=0).T)
    s = np.r_[0.0, np.cumsum(seg)]
    if s[-1] < 1e-6:
        return xy[:1]
    q = np.arange(0.0, s[-1] + 1e-9, 0.05)
    p = np.c_[np.interp(q, s, xy[:, 0]), np.interp(q, s, xy[:, 1])]
    k = max(1, int(half_m / 0.05))
    pad = np.r_[np.repeat(p[:1], k, 0), p, np.repeat(p[-1:], k, 0)]
    ker = np.ones(2 * k + 1) / (2 * k + 1)
    sm = np.c_[np.convolve(pad[:, 0], ker, "valid"), np.convolve(pad[:, 1], ker, "valid")]
    bad = world.clearance_at(sm[:, 0], sm[:, 1]) < min_clear_m
    sm[bad] = p[bad]
    return sm


def tour(world: World, clearance_m: float, length_m: float, waypoints: int,
         seed: int) -> np.ndarray:
    """A driven path (N, 2) of about ``length_m`` (5 cm apart) through
    waypoints spread over the free space, in nearest-neighbour order, then
    the same in reverse, and so on, ending where it started."""
    rng = np.random.default_rng(seed)
    blocked, k = _plan_grid(world, clearance_m)
    free = _largest_component(~blocked)
    cells = np.argwhere(free)
    wps = _farthest_points(cells, waypoints, rng)
    order = [0]
    left = list(range(1, len(wps)))
    while left:
        j = min(left, key=lambda i: np.hypot(*(wps[i] - wps[order[-1]])))
        order.append(j)
        left.remove(j)
    lap = order + [0]
    seq, lap_no, total = [0], 0, 0.0
    legs: list[np.ndarray] = []
    plan_blocked = ~free
    while True:
        nxt = lap[1:] if lap_no % 2 == 0 else lap[::-1][1:]
        for j in nxt:
            if total >= length_m and j != 0:
                continue
            a, b = wps[seq[-1]], wps[j]
            res = astar(plan_blocked, (int(a[0]), int(a[1])), (int(b[0]), int(b[1])))
            if not res.found:
                continue
            rc = np.array(res.cells, float)
            xy = (rc[:, ::-1] + 0.5) * k * world.res  # (row, col) -> (x, y)
            sm = _smooth(xy, world, 0.6 * clearance_m)
            legs.append(sm)
            total += float(np.sum(np.hypot(*np.diff(sm, axis=0).T)))
            seq.append(j)
        lap_no += 1
        if total >= length_m:
            break
    return np.vstack(legs)


def dense_poses(path: np.ndarray, turn_step_deg: float = 5.0) -> np.ndarray:
    """Poses (N, 3) along a path: heading along its tangent (over ±0.15 m),
    turning on the spot in steps of ``turn_step_deg`` where it changes more
    than that between two points (a reversal at a waypoint)."""
    keep = np.r_[True, np.hypot(*np.diff(path, axis=0).T) > 1e-4]
    p = path[keep]
    k = 3
    fwd = p[np.minimum(np.arange(len(p)) + k, len(p) - 1)]
    back = p[np.maximum(np.arange(len(p)) - k, 0)]
    d = fwd - back
    th = np.arctan2(d[:, 1], d[:, 0])
    step = math.radians(turn_step_deg)
    out = [(p[0, 0], p[0, 1], th[0])]
    for i in range(1, len(p)):
        prev = out[-1][2]
        dth = math.remainder(th[i] - prev, 2 * math.pi)
        n = int(abs(dth) // step)
        for m in range(1, n + 1):  # on the spot, at the last point
            out.append((p[i - 1, 0], p[i - 1, 1], prev + dth * m / (n + 1)))
        out.append((p[i, 0], p[i, 1], prev + dth))
    a = np.array(out)
    a[:, 2] = np.arctan2(np.sin(a[:, 2]), np.cos(a[:, 2]))
    return a


def sample_scans(poses: np.ndarray, step_m: float, turn_max_deg: float,
                 seed: int) -> np.ndarray:
    """The dense poses a thinned log keeps: the next one after ``step_m``
    (±15 %, drawn per scan) of travel or ``turn_max_deg`` of turn."""
    rng = np.random.default_rng(seed)
    turn_max = math.radians(turn_max_deg)
    keep = [0]
    dist, target = 0.0, step_m * rng.uniform(0.85, 1.15)
    for i in range(1, len(poses)):
        dist += math.hypot(*(poses[i, :2] - poses[i - 1, :2]))
        turn = abs(math.remainder(poses[i, 2] - poses[keep[-1], 2], 2 * math.pi))
        nxt_turn = abs(math.remainder(poses[min(i + 1, len(poses) - 1), 2]
                                      - poses[keep[-1], 2], 2 * math.pi))
        if dist >= target or turn >= turn_max or nxt_turn > turn_max:
            keep.append(i)
            dist, target = 0.0, step_m * rng.uniform(0.85, 1.15)
    if keep[-1] != len(poses) - 1:
        keep.append(len(poses) - 1)
    return poses[keep]
