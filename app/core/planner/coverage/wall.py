"""The tank wall as a grid of probe-wide cells (seed 001 §1–3.1).

The outer wall of a cylindrical tank is unrolled into a plane (§1: the robot
spans α = arctan(B / 2r) ≈ 0.7° of the wall, eq. 1, so the curvature is
ignored): x runs round the circumference from the shell's vertical seam, y up
from the bottom. Square cells have the probe's width D (§3.1); row r covers
y ∈ [r·D, (r+1)·D), column c covers x ∈ [c·D, (c+1)·D). A cell any part of
which an obstacle occupies is blocked (Definition 1). The wall wraps round:
column 0 and the last column are neighbours across the seam.

Obstacles (all positions in metres on the unrolled wall):

- manholes and nozzles: discs (x_m, y_m, diameter_m);
- the spiral stair: a band of given width from one point to another,
  climbing diagonally round the tank (x may run past the circumference);
- weld seams: segments; a seam the robot may not cross is blocked as a line
  of cells, one it may cross is only kept for the camera.

Cell states x_i (eq. 4): −∞ on an obstacle, 1 on a free cell, 1 − i on a
free cell visited i times.
"""

from __future__ import annotations

import json
import logging
import math
import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Disc:
    x_m: float
    y_m: float
    diameter_m: float


@dataclass(frozen=True)
class Band:
    """A straight band (stair, seam) from (x0_m, y0_m) to (x1_m, y1_m)."""

    x0_m: float
    y0_m: float
    x1_m: float
    y1_m: float
    width_m: float = 0.02
    crossable: bool = False


@dataclass(frozen=True)
class WallSpec:
    """The tank wall: 24 m × 9.6 m by default (seed 001 §1), probe D = 0.1 m."""

    diameter_m: float = 24.0
    height_m: float = 9.6
    cell_m: float = 0.1
    manholes: tuple[Disc, ...] = ()
    nozzles: tuple[Disc, ...] = ()
    stairs: tuple[Band, ...] = ()
    seams: tuple[Band, ...] = ()

    @property
    def circumference_m(self) -> float:
        return math.pi * self.diameter_m

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols) of the grid."""
        return (
            max(1, round(self.height_m / self.cell_m)),
            max(1, round(self.circumference_m / self.cell_m)),
        )


def default_wall() -> WallSpec:
    """A 24 m × 9.6 m tank: two manholes near the bottom, six nozzles, a
    spiral stair climbing a quarter of the way round, the plate seams of four
    2.4 m courses of eight plates (crossable; landmarks for the camera), and
    one repaired vertical seam the crawler must not cross."""
    return WallSpec(
        manholes=(Disc(3.0, 0.9, 0.6), Disc(40.0, 0.9, 0.6)),
        nozzles=(
            Disc(10.0, 0.5, 0.2),
            Disc(12.0, 8.5, 0.15),
            Disc(25.0, 0.6, 0.3),
            Disc(33.0, 4.0, 0.15),
            Disc(52.0, 7.8, 0.2),
            Disc(66.0, 0.5, 0.3),
        ),
        stairs=(Band(55.0, 0.0, 72.0, 9.6, 0.9),),
        seams=(Band(20.0, 2.0, 20.0, 6.0, 0.02, crossable=False), *plate_seams(24.0, 9.6)),
    )


def plate_seams(
    diameter_m: float, height_m: float, course_m: float = 2.4, plates: int = 8
) -> tuple[Band, ...]:
    """The welds of a shell built of courses ``course_m`` high, each of
    ``plates`` plates round, vertical seams staggered by half a plate from
    one course to the next: girth seams, then vertical ones (all crossable)."""
    circ = math.pi * diameter_m
    courses = max(1, round(height_m / course_m))
    out = [Band(0.0, k * course_m, circ, k * course_m, 0.01) for k in range(1, courses)]
    for k in range(courses):
        y0, y1 = k * course_m, min(height_m, (k + 1) * course_m)
        for j in range(plates):
            x = (j + 0.5 * (k % 2)) * circ / plates
            out.append(Band(x, y0, x, y1, 0.01))
    return tuple(Band(b.x0_m, b.y0_m, b.x1_m, b.y1_m, b.width_m, crossable=True) for b in out)


def shell_landmarks(spec: WallSpec) -> tuple[Band, ...]:
    """The lines a camera on the shell can see and the tank's drawing places:
    the weld seams, and the shell's bottom edge (its fillet weld to the
    bottom plate, y = 0) and top edge (y = height), as horizontal lines
    all the way round."""
    circ = spec.circumference_m
    edges = (Band(0.0, 0.0, circ, 0.0, 0.01), Band(0.0, spec.height_m, circ, spec.height_m, 0.01))
    return tuple(spec.seams) + edges


# ---- loading ----------------------------------------------------------------


def _parse(cls, raw: dict, where: str):
    names = {f.name for f in fields(cls)}
    unknown = set(raw) - names
    if unknown:
        raise ValueError(f"{where}: unknown field(s) {sorted(unknown)}; expected {sorted(names)}")
    try:
        return cls(**raw)
    except TypeError as exc:
        raise ValueError(f"{where}: {exc}") from None


def wall_from_dict(raw: dict) -> WallSpec:
    """WallSpec from a mapping (the parsed TOML or JSON); clear ValueError on
    unknown fields or non-positive sizes."""
    raw = dict(raw)
    parts = {
        "manholes": Disc,
        "nozzles": Disc,
        "stairs": Band,
        "seams": Band,
    }
    for key, cls in parts.items():
        items = raw.get(key, [])
        raw[key] = tuple(_parse(cls, dict(item), f"{key}[{i}]") for i, item in enumerate(items))
    spec = _parse(WallSpec, raw, "wall")
    for name in ("diameter_m", "height_m", "cell_m"):
        if not getattr(spec, name) > 0:
            raise ValueError(f"wall: {name} must be positive, got {getattr(spec, name)!r}")
    return spec


def load_wall(path: str | Path) -> WallSpec:
    """Read a wall description from a .toml or .json file."""
    path = Path(path)
    text = path.read_text(encoding="utf-8")
    if path.suffix == ".json":
        raw = json.loads(text)
    else:
        raw = tomllib.loads(text)
    raw = raw.get("wall", raw)
    return wall_from_dict(raw)


# ---- rasterising --------------------------------------------------------------


def _wrapped_dx(x: np.ndarray, x0: float, circ: float) -> np.ndarray:
    """Signed x − x0 taken the short way round the tank."""
    return (x - x0 + circ / 2.0) % circ - circ / 2.0


def _stamp_disc(blocked: np.ndarray, spec: WallSpec, disc: Disc) -> None:
    """Block every cell the disc touches (any part occupied, Definition 1)."""
    d = spec.cell_m
    rows, cols = blocked.shape
    yc = (np.arange(rows) + 0.5) * d
    xc = (np.arange(cols) + 0.5) * d
    dx = np.abs(_wrapped_dx(xc, disc.x_m, cols * d))
    dy = np.abs(yc - disc.y_m)
    # Distance from the disc centre to the nearest point of each cell.
    ex = np.maximum(dx - d / 2.0, 0.0)
    ey = np.maximum(dy - d / 2.0, 0.0)
    blocked |= (ey[:, None] ** 2 + ex[None, :] ** 2) < (disc.diameter_m / 2.0) ** 2


def _stamp_band(blocked: np.ndarray, spec: WallSpec, band: Band) -> None:
    """Block the cells whose centre lies within width/2 + D/2 of the band's
    centre line, so even a hair-thin seam is an unbroken line of cells that a
    move without corner cutting cannot cross."""
    d = spec.cell_m
    rows, cols = blocked.shape
    circ = cols * d
    yc = (np.arange(rows) + 0.5) * d
    xc = (np.arange(cols) + 0.5) * d
    px, py = np.meshgrid(xc, yc)
    ax, ay = band.x0_m, band.y0_m
    vx, vy = band.x1_m - ax, band.y1_m - ay
    vv = vx * vx + vy * vy
    reach = band.width_m / 2.0 + d / 2.0
    best = np.full(blocked.shape, np.inf)
    for k in (-2, -1, 0, 1, 2):  # the band may run past the seam
        qx = px + k * circ - ax
        qy = py - ay
        t = np.clip((qx * vx + qy * vy) / vv, 0.0, 1.0) if vv > 0 else np.zeros_like(qx)
        dist = np.hypot(qx - t * vx, qy - t * vy)
        best = np.minimum(best, dist)
    blocked |= best <= reach


def rasterise(spec: WallSpec) -> np.ndarray:
    """The wall's occupancy grid: bool (rows, cols), True = blocked."""
    blocked = np.zeros(spec.shape, dtype=bool)
    for disc in (*spec.manholes, *spec.nozzles):
        _stamp_disc(blocked, spec, disc)
    for band in spec.stairs:
        _stamp_band(blocked, spec, band)
    for band in spec.seams:
        if not band.crossable:
            _stamp_band(blocked, spec, band)
    log.debug("wall %s: %d of %d cells blocked", spec.shape, int(blocked.sum()), blocked.size)
    return blocked


# ---- cell states and neighbours -------------------------------------------------


def cell_states(blocked: np.ndarray, visits: np.ndarray | None = None) -> np.ndarray:
    """x_i of every cell (eq. 4): −∞ blocked, 1 free, 1 − i after i visits."""
    x = np.ones(blocked.shape, dtype=float)
    if visits is not None:
        x -= np.asarray(visits, dtype=float)
    x[np.asarray(blocked, dtype=bool)] = -np.inf
    return x


MOVES = ((-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (-1, 1), (1, -1), (1, 1))


def neighbours(blocked: np.ndarray, r: int, c: int, wrap: bool = True) -> list[tuple[int, int]]:
    """The cells one move from (r, c): eight neighbours, free, a diagonal only
    when both cells it passes are free; across the seam when ``wrap``."""
    rows, cols = blocked.shape
    out = []
    for dr, dc in MOVES:
        nr, nc = r + dr, c + dc
        if not 0 <= nr < rows:
            continue
        if not 0 <= nc < cols:
            if not wrap:
                continue
            nc %= cols
        if blocked[nr, nc]:
            continue
        if dr and dc and (blocked[nr, c] or blocked[r, nc]):
            continue
        out.append((nr, nc))
    return out


@dataclass
class WallGrid:
    """A rasterised wall with its visit counts (the x_i of eq. 4 live)."""

    spec: WallSpec
    blocked: np.ndarray = field(init=False)
    visits: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.blocked = rasterise(self.spec)
        self.visits = np.zeros(self.blocked.shape, dtype=np.int32)

    def states(self) -> np.ndarray:
        return cell_states(self.blocked, self.visits)

    def cell_of(self, x_m: float, y_m: float) -> tuple[int, int]:
        d = self.spec.cell_m
        rows, cols = self.blocked.shape
        return (min(rows - 1, max(0, int(y_m // d))), int((x_m // d) % cols))
