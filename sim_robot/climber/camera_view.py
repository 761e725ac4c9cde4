"""The climber's downward camera as pixels: what the lens under the probe sees
of the steel shell, drawn from the simulated wall (truth: the simulator's
side only; the robot gets the picture, never the geometry behind it).

The view is square, ``px`` pixels of ``m_per_px`` metres (160 px of 1 mm by
default: ±8 cm round the image centre, the oracle sightings' range). Image
rows run against the body's forward axis (up in the image is forward), columns
against its left (right in the image is the body's right). What is drawn:

- the plate: mid grey with a blotchy mill scale (a low-frequency field) and
  sensor noise;
- weld seams (girth and vertical, :func:`shell_landmarks`'s lines) as beads
  of the band's width, brighter in the middle (lit from the camera's ring
  light), with a ripple along the weld and dark toes at both sides;
- the shell's bottom edge: the fillet weld's bead centred on y = 0 and the
  bottom plate below it, darker; the top edge: the plate ends at y = height
  and the void beyond is dark;
- manholes and nozzles: their opening dark, their neck's weld a bright ring
  just outside the rim;
- the ring light's fall-off towards the corners, a random tilt of the light,
  defocus and noise, different each frame.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from app.core.planner.coverage.wall import shell_landmarks

PX = 160
M_PER_PX = 0.001
PLATE = 118.0
BEAD = 48.0  # the bead's crown above the plate
TOE = -34.0  # its toes
TOE_M = 0.0015
VOID = 24.0  # beyond the top edge
BOTTOM_PLATE = 78.0
OPENING = 34.0
NECK = 190.0
NECK_M = 0.006


def _grid(x_m: float, y_m: float, theta: float, px: int, m: float):
    """The wall point (x, y) of every pixel, and the body-frame along-axis of each."""
    k = (np.arange(px, dtype=np.float32) - (px - 1) / 2) * m
    fwd = -k[:, None] + np.zeros((1, px), np.float32)  # rows: up is forward
    left = np.zeros((px, 1), np.float32) - k[None, :]  # columns: right is the body's right
    c, s = math.cos(theta), math.sin(theta)
    return x_m + fwd * c - left * s, y_m + fwd * s + left * c


def _bead(d: np.ndarray, along: np.ndarray, width: float) -> np.ndarray:
    """A weld bead's brightness over the plate at distance ``d`` from its axis."""
    half = width / 2
    crown = np.clip(1.0 - (d / half) ** 2, 0.0, None)
    ripple = 0.85 + 0.15 * np.sin(along * (2 * math.pi / 0.004))
    toe = (np.abs(d) >= half) & (np.abs(d) < half + TOE_M)
    return BEAD * np.sqrt(crown) * ripple + TOE * toe


def render_view(world, x_m: float, y_m: float, theta: float, rng: np.random.Generator,
                px: int = PX, m_per_px: float = M_PER_PX) -> np.ndarray:
    """The camera's grey frame (uint8, px × px) centred on (x_m, y_m) of ``world``
    (a :class:`~.wall_world.WallWorld`), the body facing ``theta``."""
    wx, wy = _grid(x_m, y_m, theta, px, m_per_px)
    circ, height = world.circ_m, world.spec.height_m
    # mill scale: a coarse random field, smoothly enlarged
    coarse = rng.normal(0.0, 9.0, (6, 6)).astype(np.float32)
    img = PLATE + cv2.resize(coarse, (px, px), interpolation=cv2.INTER_CUBIC)
    for band in shell_landmarks(world.spec)[:-2]:  # the seams (the edges below)
        if band.y0_m == band.y1_m:
            d = wy - band.y0_m
            img += _bead(d, wx, band.width_m)
        elif band.x0_m == band.x1_m:
            lo, hi = sorted((band.y0_m, band.y1_m))
            d = (wx - band.x0_m + circ / 2) % circ - circ / 2
            img += _bead(d, wy, band.width_m) * ((wy >= lo) & (wy <= hi))
    # the bottom: fillet weld on y = 0, bottom plate below; the top: nothing beyond
    img = np.where(wy < -0.006, BOTTOM_PLATE + 0.5 * (img - PLATE), img)
    img += _bead(wy, wx, 0.012)
    img = np.where(wy > height, VOID, img)
    for disc in (*world.spec.manholes, *world.spec.nozzles):
        dx = (wx - disc.x_m + circ / 2) % circ - circ / 2
        rho = np.hypot(dx, wy - disc.y_m)
        r = disc.diameter_m / 2
        img = np.where(rho < r, OPENING, np.where(rho < r + NECK_M, NECK, img))
    # the ring light: fall-off to the corners, a random tilt; defocus; noise
    k = np.linspace(-1.0, 1.0, px, dtype=np.float32)
    r2 = k[:, None] ** 2 + k[None, :] ** 2
    tilt = rng.normal(0.0, 0.08, 2)
    img *= (1.0 - 0.18 * r2) * (1.0 + tilt[0] * k[None, :] + tilt[1] * k[:, None])
    img = cv2.GaussianBlur(img, (0, 0), float(rng.uniform(0.5, 1.4)))
    img += rng.normal(0.0, 3.5, img.shape).astype(np.float32)
    return np.clip(img, 0, 255).astype(np.uint8)
