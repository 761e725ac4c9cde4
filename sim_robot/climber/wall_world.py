"""The tank wall the climber crawls on: obstacles, weld seams and the true
steel thickness with corroded patches (ground truth: never sent to a desk).

The geometry is the planner's wall (app/core/planner/coverage/wall.py,
seed 001 §1–3.1): the outer shell unrolled, x round the tank (wrapping at the
circumference), y up, cells of the probe's width D. The thickness is a
nominal plate thickness minus Gaussian-shaped corrosion patches; the
ultrasonic probe reads the mean thickness under its cell with a little noise.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from app.core.planner.coverage.wall import (
    Band,
    WallSpec,
    default_wall,
    rasterise,
    shell_landmarks,
)

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Patch:
    """A corroded patch: centre, radius (1σ) and depth of metal lost."""

    x_m: float
    y_m: float
    radius_m: float
    loss_mm: float


def random_patches(spec: WallSpec, rng: np.random.Generator, count: int = 6) -> tuple[Patch, ...]:
    circ = spec.circumference_m
    return tuple(
        Patch(
            float(rng.uniform(0, circ)),
            float(rng.uniform(0.2, spec.height_m - 0.2)),
            float(rng.uniform(0.1, 0.5)),
            float(rng.uniform(0.5, 3.5)),
        )
        for _ in range(count)
    )


class WallMap:
    """The wall as the robot knows it from its drawing: the planner's raster of
    obstacles, seams and cells, the nominal plate thickness; no truth (the
    relay's map; with a real board, ``sim-robot --serial``, all there is)."""

    def __init__(self, spec: WallSpec | None = None, nominal_mm: float = 10.0) -> None:
        self.spec = spec or default_wall()
        self.blocked = rasterise(self.spec)
        self.rows, self.cols = self.blocked.shape
        self.cell_m = self.spec.cell_m
        self.circ_m = self.cols * self.cell_m
        self.nominal_mm = nominal_mm

    # ---- geometry ----------------------------------------------------------------

    def wrap_dx(self, dx: float) -> float:
        return (dx + self.circ_m / 2) % self.circ_m - self.circ_m / 2

    def cell_of(self, x_m: float, y_m: float) -> tuple[int, int] | None:
        """(row, col) under the point, None off the top or bottom of the wall."""
        r = math.floor(y_m / self.cell_m)
        if not 0 <= r < self.rows:
            return None
        return r, math.floor((x_m % self.circ_m) / self.cell_m)

    def cell_centre(self, row: int, col: int) -> tuple[float, float]:
        return ((col + 0.5) * self.cell_m, (row + 0.5) * self.cell_m)

    def footprint_free(
        self, x_m: float, y_m: float, theta_rad: float, length_m: float, width_m: float
    ) -> bool:
        """The body's rectangle touches no obstacle and stays on the wall
        (:meth:`.contact.WallContact.depth`, the simulator's own check)."""
        from .contact import WallContact

        return WallContact(self.spec, self.blocked, length_m, width_m).depth(
            x_m, y_m, theta_rad)[0] <= 0.0


class WallWorld(WallMap):
    """The simulated wall: the map, and the truth a real robot only samples (the
    thickness, what the camera sees)."""

    def __init__(
        self,
        spec: WallSpec | None = None,
        nominal_mm: float = 10.0,
        patches: tuple[Patch, ...] | None = None,
        seed: int = 0,
        probe_noise_mm: float = 0.03,
    ) -> None:
        super().__init__(spec, nominal_mm)
        self.rng = np.random.default_rng(seed)
        self.patches = patches if patches is not None else random_patches(self.spec, self.rng)
        self.probe_noise_mm = probe_noise_mm
        self.thickness = self._thickness_grid()

    # ---- thickness -----------------------------------------------------------------

    def _thickness_grid(self) -> np.ndarray:
        yc = (np.arange(self.rows) + 0.5) * self.cell_m
        xc = (np.arange(self.cols) + 0.5) * self.cell_m
        t = np.full((self.rows, self.cols), self.nominal_mm)
        for p in self.patches:
            dx = (xc - p.x_m + self.circ_m / 2) % self.circ_m - self.circ_m / 2
            dy = yc - p.y_m
            t -= p.loss_mm * np.exp(-(dy[:, None] ** 2 + dx[None, :] ** 2) / (2 * p.radius_m**2))
        return t

    def thinnest(self) -> tuple[float, tuple[int, int]]:
        """The true minimum over free cells and where it is (for evaluation)."""
        t = np.where(self.blocked, np.inf, self.thickness)
        i = np.unravel_index(int(np.argmin(t)), t.shape)
        return float(t[i]), (int(i[0]), int(i[1]))

    def probe(self, x_m: float, y_m: float) -> float | None:
        """Ultrasonic thickness reading (mm) at the probe's cell; None off the
        wall or over an obstacle (no coupling)."""
        cell = self.cell_of(x_m, y_m)
        if cell is None or self.blocked[cell]:
            return None
        return float(self.thickness[cell] + self.probe_noise_mm * self.rng.standard_normal())

    # ---- camera ----------------------------------------------------------------------

    def seams_in_view(
        self, x_m: float, y_m: float, range_m: float = 0.5
    ) -> list[tuple[Band, float]]:
        """Weld seams within range of the camera at (x, y): (seam, distance)."""
        out = []
        for band in self.spec.seams:
            d = self._distance(band, x_m, y_m)
            if d <= range_m:
                out.append((band, d))
        return out

    def _distance(self, band: Band, x_m: float, y_m: float) -> float:
        """From (x, y) to the band's centre line, round the tank: the point is
        tried at its wrapped offset from the band's start and one turn either
        side, so a band as long as the circumference is near everywhere."""
        ax, ay = band.x0_m, band.y0_m
        vx, vy = band.x1_m - ax, band.y1_m - ay
        vv = vx * vx + vy * vy
        qy = y_m - ay
        best = math.inf
        for turn in (-1, 0, 1):
            qx = self.wrap_dx(x_m - ax) + turn * self.circ_m
            t = min(1.0, max(0.0, (qx * vx + qy * vy) / vv)) if vv > 0 else 0.0
            best = min(best, math.hypot(qx - t * vx, qy - t * vy))
        return best

    def rim_sightings(
        self,
        x_m: float,
        y_m: float,
        theta_rad: float,
        rng: np.random.Generator,
        range_m: float = 0.08,
        noise_m: float = 0.003,
        angle_noise_rad: float = 0.002,
    ) -> list[tuple[float, float, float, float]]:
        """What the downward camera at (x, y) sees of the rims of manholes and
        nozzles within ``range_m`` of its image centre: for each, the offsets
        from the image centre to the nearest point of the rim and to its
        centre, in the body frame ``(near_fwd, near_left, centre_fwd,
        centre_left)``; the nearest point with ``noise_m``, the direction from
        it to the centre with ``angle_noise_rad`` (the camera's: 1–1.5 mrad rms,
        docs/climber.md)."""
        out = []
        c, s = math.cos(theta_rad), math.sin(theta_rad)
        for disc in (*self.spec.manholes, *self.spec.nozzles):
            dx, dy = self.wrap_dx(x_m - disc.x_m), y_m - disc.y_m
            rho = math.hypot(dx, dy)
            r = disc.diameter_m / 2
            if rho < 1e-9 or abs(rho - r) > range_m:
                continue
            ox, oy = dx * (r / rho - 1.0), dy * (r / rho - 1.0)  # to the rim, wall frame
            n = noise_m * rng.standard_normal(2)
            a = math.atan2(-dy, -dx) + angle_noise_rad * float(rng.standard_normal())
            qx, qy = ox + float(n[0]), oy + float(n[1])  # the rim point seen, wall frame
            mx, my = qx + r * math.cos(a), qy + r * math.sin(a)  # the centre seen
            out.append((c * qx + s * qy, -s * qx + c * qy, c * mx + s * my, -s * mx + c * my))
        return out

    def seam_sightings(
        self,
        x_m: float,
        y_m: float,
        theta_rad: float,
        rng: np.random.Generator,
        range_m: float = 0.08,
        offset_noise_m: float = 0.003,
        angle_noise_rad: float = math.radians(1.0),
    ) -> list[tuple[bool, float, float]]:
        """What the downward camera at (x, y) sees of the girth (horizontal)
        and vertical seams and of the shell's bottom and top edges
        (:func:`shell_landmarks`) within ``range_m`` of its image centre:
        ``(horizontal, direction in the image relative to the heading,
        signed offset of the seam from the image centre along the wall's y
        for a girth seam, x for a vertical one)``, with noise."""
        out = []
        for band in shell_landmarks(self.spec):
            if self._distance(band, x_m, y_m) > range_m:
                continue
            flat = band.y0_m == band.y1_m
            if not flat and band.x0_m != band.x1_m:
                continue  # the shell's seams are girth or vertical
            if flat:
                offset = band.y0_m - y_m
            else:
                lo, hi = sorted((band.y0_m, band.y1_m))
                if not lo <= y_m <= hi:
                    continue  # past the seam's end: no line through the image
                offset = self.wrap_dx(band.x0_m - x_m)
            angle = (0.0 if flat else math.pi / 2) - theta_rad
            out.append(
                (
                    flat,
                    angle + angle_noise_rad * float(rng.standard_normal()),
                    offset + offset_noise_m * float(rng.standard_normal()),
                )
            )
        return out
