"""Occupancy grids: built from laser landmarks (log-odds), saved and loaded in
the ROS map_server format (YAML + PGM), unknown cells kept unknown.

Cells hold −1 (unknown), 0 (free) or 100 (occupied), row 0 at the lowest y,
as app/core/planner's GridMap; ``origin_xy`` is the lower-left corner of
cell (0, 0). The PGM has image row 0 at the top and uses the map_server
trinary values: 0 occupied, 254 free, 205 unknown (p = (255 − v)/255 lies
between free_thresh and occupied_thresh).

Building (seed 002 §2.3, the map made of the landmarks' scans): each beam adds
``l_occ`` to the log-odds of its end cell and ``l_free`` to the cells it
crossed; a cell is occupied above ``+threshold``, free below ``−threshold``,
unknown otherwise (never touched, or contradictory). The sum counts hits
against misses (occupied where l_occ·hits + l_free·misses > threshold), so
an object that stood somewhere for a while and went is cleared once later
beams cross its cells about 1.5 times as often as it was seen (at the
defaults; the mapping mode's map, 3 times: sim_robot/mapping_mode.py); the beams
that came back with nothing cross cells too (``free_scans``, free_space.py),
or a mover seen only against open ground would never be.

This module is the one writer of map files: app/core/planner's save_ros_map
and the simulator's map export go through ``save_map``.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numba import njit

from .se2 import transform_points

log = logging.getLogger(__name__)

UNKNOWN, FREE, OCCUPIED = -1, 0, 100
PGM_OCCUPIED, PGM_FREE, PGM_UNKNOWN = 0, 254, 205


@dataclass
class OccupancyGrid:
    cells: np.ndarray  # int8, −1 / 0 / 100, [row = y, col = x]
    resolution_m: float
    origin_xy: tuple[float, float]

    @property
    def occupied(self) -> np.ndarray:
        return self.cells == OCCUPIED

    @property
    def unknown(self) -> np.ndarray:
        return self.cells == UNKNOWN


def build_grid(poses: np.ndarray, scans: list[np.ndarray], resolution_m: float = 0.05,
               l_occ: float = 0.9, l_free: float = -0.6, threshold: float = 0.5,
               margin_m: float = 1.0,
               free_scans: list[np.ndarray] | None = None,
               stop_at_surface: bool = False) -> OccupancyGrid:
    """Log-odds grid from scans (points in the sensor frame) taken at ``poses``.
    Per scan, a cell takes ``l_occ`` once if a beam ends in it, else
    ``l_free`` once if a beam crosses it (sampled every half cell up to one
    cell short of the end); compiled (``_accumulate``), so a map may be built
    from every scan, not only the keyframes. ``free_scans``: per scan, the
    end points of its beams that returned nothing (free_space.no_return_rays),
    free all the way to their end, and never over a cell a beam of the same
    scan ended in. ``stop_at_surface``: a return's free ray stops one cell off
    the surface it ended on (the segments to its neighbouring returns,
    ``_surface_stop``), not one cell short of its end along the ray: a beam
    at a grazing angle to a wall runs within a cell of it for several cells
    before its end, and at one cell short it crossed the near part of the
    wall's face cells farther back, where the face lies inside its cells
    rather than on their edge (tests/localisation/test_map_io.py)."""
    poses = np.asarray(poses, float).reshape(-1, 3)
    if free_scans is None:
        free_scans = [np.zeros((0, 2))] * len(poses)
    pairs = list(zip(poses, scans, free_scans, strict=True))
    world = [transform_points(p, np.asarray(s, float)) for p, *ss in pairs for s in ss if len(s)]
    allpts = np.vstack(world + [poses[:, :2]])
    # the cells' corners on multiples of the resolution in the poses' frame: the
    # grid does not shift by a fraction of a cell as the map grows (each cell
    # of the live map stays where it was) or when a far free ray widens it
    lo = np.floor((allpts.min(axis=0) - margin_m) / resolution_m) * resolution_m
    hi = allpts.max(axis=0) + margin_m
    w, h = (np.ceil((hi - lo) / resolution_m).astype(int) + 1)
    logodds = np.zeros(h * w, np.float32)
    end_mark = np.full(h * w, -1, np.int32)  # the last scan whose beam ended in the cell
    free_mark = np.full(h * w, -1, np.int32)  # ...and crossed it
    for n, (pose, pts, free) in enumerate(pairs):
        if not len(pts) and not len(free):
            continue
        end = np.ascontiguousarray(transform_points(pose, np.asarray(pts, float).reshape(-1, 2)),
                                   dtype=float)
        open_end = np.ascontiguousarray(
            transform_points(pose, np.asarray(free, float).reshape(-1, 2)), dtype=float)
        _accumulate(logodds, end_mark, free_mark, n, float(pose[0]), float(pose[1]), end,
                    open_end, float(lo[0]), float(lo[1]), float(resolution_m), int(w), int(h),
                    float(l_occ), float(l_free), bool(stop_at_surface))
    logodds = logodds.reshape(h, w)
    cells = np.full((h, w), UNKNOWN, np.int8)
    cells[logodds > threshold] = OCCUPIED
    cells[logodds < -threshold] = FREE
    return OccupancyGrid(cells, resolution_m, (float(lo[0]), float(lo[1])))


@njit(cache=True)
def _accumulate(logodds, end_mark, free_mark, scan, ox, oy, end, open_end, lox, loy, res, w, h,
                l_occ, l_free, stop_at_surface):
    """One scan's beams from (ox, oy) into the flat log-odds grid (build_grid):
    ``end`` the returns, ``open_end`` the ends of the free rays of the beams
    that returned nothing."""
    n = end.shape[0]
    for i in range(n):
        cx = int(math.floor((end[i, 0] - lox) / res))
        cy = int(math.floor((end[i, 1] - loy) / res))
        if 0 <= cx < w and 0 <= cy < h:
            c = cy * w + cx
            if end_mark[c] != scan:
                end_mark[c] = scan
                logodds[c] += l_occ
    for i in range(n):
        short = res
        if stop_at_surface:
            short = max(res, _surface_stop(ox, oy, end, i, res))
        _free_ray(logodds, end_mark, free_mark, scan, ox, oy, end[i, 0], end[i, 1], lox, loy,
                  res, w, h, l_free, -short)
    for i in range(open_end.shape[0]):
        _free_ray(logodds, end_mark, free_mark, scan, ox, oy, open_end[i, 0], open_end[i, 1],
                  lox, loy, res, w, h, l_free, 0.0)


@njit(cache=True)
def _surface_stop(ox, oy, end, i, band):
    """How far short of its end the free ray of return ``i`` must stop to keep
    ``band`` metres off the surface it ended on, taken as the segments from
    the return to its neighbours in the scan (the points are in beam order)
    that lie back towards the sensor: ``band / sin θ`` along the ray for a
    segment at θ to it, at most as far back as the neighbour lies."""
    n = end.shape[0]
    ux, uy = end[i, 0] - ox, end[i, 1] - oy
    r = math.hypot(ux, uy)
    if r <= 0.0:
        return 0.0
    ux, uy = ux / r, uy / r
    short = 0.0
    for j in (i - 1, i + 1):
        if j < 0 or j >= n:
            continue
        vx, vy = end[j, 0] - end[i, 0], end[j, 1] - end[i, 1]
        back = -(vx * ux + vy * uy)  # how far back along the ray the neighbour lies
        if back <= 0.0:
            continue  # beyond the end: the ray does not run along that segment
        sin_t = abs(ux * vy - uy * vx) / math.hypot(vx, vy)
        short = max(short, back if sin_t * back <= band else band / sin_t)
    return short


@njit(cache=True)
def _free_ray(logodds, end_mark, free_mark, scan, ox, oy, ex, ey, lox, loy, res, w, h, l_free,
              extend):
    """``l_free`` once per scan into each cell the ray from (ox, oy) towards
    (ex, ey) crosses, sampled every half cell up to ``extend`` metres past
    the end (negative: short of it), never into a cell a beam of the same
    scan ended in."""
    dx, dy = ex - ox, ey - oy
    length = math.hypot(dx, dy)
    if length <= res:
        return
    stop = 1.0 + extend / length
    step = 0.5 * res / length
    k = 0
    while k * step < stop:
        f = k * step
        cx = int(math.floor((ox + f * dx - lox) / res))
        cy = int(math.floor((oy + f * dy - loy) / res))
        k += 1
        if 0 <= cx < w and 0 <= cy < h:
            c = cy * w + cx
            if end_mark[c] != scan and free_mark[c] != scan:
                free_mark[c] = scan
                logodds[c] += l_free


# ---- ROS map_server files --------------------------------------------------------------


def save_map(grid: OccupancyGrid, yaml_path: str | Path, image_suffix: str = ".pgm") -> Path:
    """Write YAML + image (PGM unless told); unknown cells as 205."""
    yaml_path = Path(yaml_path)
    img_path = yaml_path.with_suffix(image_suffix)
    img = np.full(grid.cells.shape, PGM_UNKNOWN, np.uint8)
    img[grid.cells == FREE] = PGM_FREE
    img[grid.cells == OCCUPIED] = PGM_OCCUPIED
    if not cv2.imwrite(str(img_path), np.flipud(img)):
        raise OSError(f"cannot write {img_path}")
    ox, oy = grid.origin_xy
    yaml_path.write_text(
        f"image: {img_path.name}\nmode: trinary\nresolution: {grid.resolution_m}\n"
        f"origin: [{ox}, {oy}, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
        encoding="utf-8")
    return yaml_path


def _parse_small_yaml(text: str, source: str) -> dict[str, object]:
    """The flat ``key: value`` YAML of a map file: numbers, strings and one-line
    ``[a, b, c]`` lists; comments (#) dropped."""
    out: dict[str, object] = {}
    for lineno, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        if ":" not in line:
            raise ValueError(f"{source} line {lineno}: expected 'key: value', got {raw!r}")
        key, value = (s.strip() for s in line.split(":", 1))
        if value.startswith("[") and value.endswith("]"):
            out[key] = [_scalar(v.strip()) for v in value[1:-1].split(",") if v.strip()]
        else:
            out[key] = _scalar(value)
    return out


def _scalar(v: str) -> object:
    if len(v) >= 2 and v[0] == v[-1] and v[0] in "'\"":
        return v[1:-1]
    for conv in (int, float):
        try:
            return conv(v)
        except ValueError:
            pass
    if v.lower() in ("true", "false"):
        return v.lower() == "true"
    return v


def load_map(yaml_path: str | Path) -> OccupancyGrid:
    """Read a map_server YAML + image (trinary): p = (255 − v)/255 (v/255 when
    negate: 1); p > occupied_thresh occupied, p < free_thresh free, else unknown.
    A bad file raises ValueError with the file's name."""
    yaml_path = Path(yaml_path)
    meta = _parse_small_yaml(yaml_path.read_text(encoding="utf-8"), str(yaml_path))
    for key in ("image", "resolution", "origin"):
        if key not in meta:
            raise ValueError(f"{yaml_path}: missing '{key}'")
    img_path = Path(str(meta["image"]))
    if not img_path.is_absolute():
        img_path = yaml_path.parent / img_path
    img = cv2.imread(str(img_path), cv2.IMREAD_UNCHANGED)
    if img is None:
        raise ValueError(f"{yaml_path}: cannot read image {img_path}")
    if img.ndim == 3:
        img = cv2.cvtColor(img[:, :, :3], cv2.COLOR_BGR2GRAY)
    if img.dtype != np.uint8:
        img = (img.astype(np.float64) * 255.0 / float(np.iinfo(img.dtype).max)).astype(np.uint8)
    v = img.astype(np.float64) / 255.0
    p = v if int(meta.get("negate", 0)) else 1.0 - v
    occ_t = float(meta.get("occupied_thresh", 0.65))
    free_t = float(meta.get("free_thresh", 0.196))
    cells = np.full(img.shape, UNKNOWN, np.int8)
    cells[p > occ_t] = OCCUPIED
    cells[p < free_t] = FREE
    origin = meta["origin"]
    if not isinstance(origin, list) or len(origin) < 2:
        raise ValueError(f"{yaml_path}: origin must be [x, y, yaw]")
    if len(origin) > 2 and float(origin[2]) != 0.0:
        log.warning("%s: map yaw %.3f rad is ignored", yaml_path, float(origin[2]))
    res = float(meta["resolution"])  # type: ignore[arg-type]
    if not res > 0:
        raise ValueError(f"{yaml_path}: resolution must be positive")
    return OccupancyGrid(np.flipud(cells).copy(), res, (float(origin[0]), float(origin[1])))
