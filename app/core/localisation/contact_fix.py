"""A contact with the wall's mapped obstacles or edges as a position fix for the
wall climber's estimate (:class:`.wall_ekf.WallEkf`).

Why: in the stair band's part of the tank the vertical weld seams, the only
landmarks that fix x (along the wall), are hidden by the band or lie too far
along the rows for a detour, and the nozzles' rims are seen only by the few
lanes that pass within the camera's 8 cm of them. There x drifts 8–15 cm
between fixes, more than the 2 cm margin the moves keep, and the body
touches the band (a staircase of map cells) or, under a nozzle by the shell's
bottom, steps into it and wedges. What the robot does have at such a moment
is the board's contact flag: the body stopped because its footprint reached
an edge or an obstacle of the map. Where the body stands therefore lies on the
map's *contact set*: the poses where the footprint (288 × 260 mm) just
touches something, depth(x, y, θ) ≈ 0 — a curve in (x, y) for the heading,
which the gravity heading keeps within a fraction of a degree. The stair's
lower side runs at 29.5° to the rows, so the curve's normal is mostly y and
partly x; with y known from the girth seams and the shell's edges to a cm
or two, a touch of the band tells x.

A contact is ambiguous (which face of which obstacle?), and the map's band is
a staircase of 0.1 m cells (the simulator's body stops against the same
raster), so no single face's normal is right to linearise on: a body whose
height is known to 1–2 cm touches one tread of the staircase, which tells x
to within the tread's 10 cm, not to a line. The fix is therefore found by
search, as the belief conditioned on touching:

1. the poses on a grid in (x, y) about the belief (θ the belief's, which the
   gravity heading keeps within a fraction of a degree; the grid's step half
   the belief's smaller σ, 2 mm to 1 cm), within ``window`` σ of it, whose
   footprint touches the map to within half a step are the candidates (the
   body stops at the first overlap);
2. when there are none, or the nearest is more than ``surprise`` σ from the
   belief, the belief hardly explains the contact: it is over-sure or off
   (a belief 10 cm off in x and sure of it to 2 cm would otherwise take a
   contact with the band's lower side as a y error), and its x and y variances are opened to
   at least ``floor_sigma_m`` and ``floor_sigma_y_m`` and the search made
   again;
3. they are weighted by the belief's Gaussian; when they fall apart into more
   than one connected piece of weight (two faces at once: the bottom edge and
   a nozzle) the contact is ambiguous and nothing is fixed;
4. else their weighted mean and covariance are the belief's (x, y) given the
   contact, and one two-dimensional update on x and y brings the filter's
   marginal to them (the measurement's noise is (C⁻¹ − P⁻¹)⁻¹, the
   information the contact adds; a direction it adds none to gets none), so
   the correlated states (the slip, the accelerometer's bias) follow as they
   do for a landmark;
5. when still no grid pose touches, the contact is not explained by the
   belief (something not on the map, a heading far off) and is not used.

The depth function is the map's footprint check (the caller's, e.g.
``sim_robot.climber.contact.WallContact.depth`` on the relay's map): no ground
truth.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .wall_ekf import WallEkf, X, Y

Depth = Callable[[float, float, float, float], float]


@dataclass(frozen=True)
class ContactFixConfig:
    grid_m: float = 0.01  # the search grid's step: half the belief's smaller σ, at most this
    min_grid_m: float = 0.002  # ... and at least this
    window: float = 3.0  # half-width of the search, in the belief's σ ...
    max_half_m: float = 0.3  # ... at most this
    floor_sigma_m: float = 0.05  # an over-sure belief (see surprise): its x σ opened to this,
    floor_sigma_y_m: float = 0.01  # its y σ to this (y has its girth seams and edges)
    surprise: float = 2.0  # the nearest touching pose further than this many σ: over-sure
    min_share: float = 0.1  # a second connected piece of this much weight: ambiguous
    max_move_m: float = 0.25  # a fix moving the belief further than this is not made


@dataclass
class ContactFix:
    """What one contact did: ``fixed`` (an update made), ``why`` (otherwise),
    the number of touching poses found and how far the believed x and y moved."""

    fixed: bool
    why: str = ""
    poses: int = 0
    dx_m: float = 0.0
    dy_m: float = 0.0


def _pieces(cells: np.ndarray, w: np.ndarray) -> list[float]:
    """The weight of each 8-connected piece of the grid cells (integer (i, j) rows)."""
    index = {(int(i), int(j)): k for k, (i, j) in enumerate(cells)}
    seen = np.zeros(len(cells), bool)
    out = []
    for k0 in range(len(cells)):
        if seen[k0]:
            continue
        seen[k0] = True
        stack, total = [k0], 0.0
        while stack:
            k = stack.pop()
            total += float(w[k])
            i, j = cells[k]
            for di in (-1, 0, 1):
                for dj in (-1, 0, 1):
                    n = index.get((int(i) + di, int(j) + dj))
                    if n is not None and not seen[n]:
                        seen[n] = True
                        stack.append(n)
        out.append(total)
    return sorted(out, reverse=True)


def _touching(ekf: WallEkf, depth: Depth, cfg: ContactFixConfig) -> tuple[float, list]:
    """The grid's step and the (i, j) grid poses about the belief within the search
    window whose footprint touches the map (within half a step: the body stops at
    the first overlap, to a hundredth of a mm in the simulator)."""
    x0, y0, th = ekf.pose
    p = ekf.covariance
    sx, sy = (math.sqrt(max(0.0, p[k, k])) for k in (X, Y))
    grid = min(cfg.grid_m, max(cfg.min_grid_m, min(sx, sy) / 2))
    ni, nj = (max(2, math.ceil(min(cfg.max_half_m, cfg.window * s) / grid)) for s in (sx, sy))
    cells = []
    for j in range(-nj, nj + 1):
        for i in range(-ni, ni + 1):
            x, y = x0 + i * grid, y0 + j * grid
            if depth(x, y, th, grid / 2) > 0.0 and depth(x, y, th, 0.0) <= grid / 2:
                cells.append((i, j))
    return grid, cells


def _surprise(ekf: WallEkf, grid: float, cells: list) -> float:
    """How many of the belief's σ the nearest touching pose is from it (inf: none)."""
    if not cells:
        return math.inf
    q = np.asarray(cells) * grid
    pinv = np.linalg.inv(ekf.covariance[np.ix_((X, Y), (X, Y))])
    return math.sqrt(float(np.einsum("ij,jk,ik->i", q, pinv, q).min()))


def contact_fix(ekf: WallEkf, depth: Depth, cfg: ContactFixConfig | None = None) -> ContactFix:
    """The body stopped against the map (the board's contact flag): fold that
    into ``ekf`` as above. ``depth(x, y, θ, grow)``: how far the footprint at
    that pose, grown by ``grow`` on every side, reaches into the map's edges or
    obstacles (≤ 0 clear; a clear footprint's distance need not be told)."""
    cfg = cfg or ContactFixConfig()
    x0, y0, th = ekf.pose
    grid, cells = _touching(ekf, depth, cfg)
    if _surprise(ekf, grid, cells) > cfg.surprise:  # the belief is over-sure, or off
        ekf.open_variance(X, cfg.floor_sigma_m)
        ekf.open_variance(Y, cfg.floor_sigma_y_m)
        grid, cells = _touching(ekf, depth, cfg)
    if not cells:
        return ContactFix(False, "no pose near the belief touches the map")
    p = ekf.covariance[np.ix_((X, Y), (X, Y))]
    c = np.asarray(cells)
    q = c * grid
    pinv = np.linalg.inv(p)
    m2 = np.einsum("ij,jk,ik->i", q, pinv, q)
    w = np.exp(-0.5 * (m2 - m2.min()))
    w /= w.sum()
    pieces = _pieces(c, w)
    if len(pieces) > 1 and pieces[1] >= cfg.min_share:
        return ContactFix(False, f"ambiguous ({len(pieces)} pieces)", len(cells))
    mean = w @ q
    dq = q - mean
    cov = (dq * w[:, None]).T @ dq + np.eye(2) * grid**2 / 12
    if math.hypot(*mean) > cfg.max_move_m:
        return ContactFix(False, "too far from the belief", len(cells))
    # the contact's information, C⁻¹ − P⁻¹, as a measurement of (x, y) with noise R
    vals, vecs = np.linalg.eigh(np.linalg.inv(cov) - pinv)
    vals = np.maximum(vals, 1e-4)  # a direction the contact tells nothing of: R of 100 m
    r = vecs @ np.diag(1.0 / vals) @ vecs.T
    # the measurement z whose update moves the (x, y) marginal's mean by ``mean``
    z_off = (np.eye(2) + r @ pinv) @ mean
    h = np.zeros((2, ekf.n))
    h[0, X] = h[1, Y] = 1.0
    ekf.update(h @ ekf.state + z_off, h, r)
    x1, y1, _ = ekf.pose
    return ContactFix(True, "", len(cells), x1 - x0, y1 - y0)


class ContactFixes:
    """Contact fixes, one per place. A contact within ``apart_m`` of where the belief
    was at the last fix is the body pressed again against what it touched then (a
    recoil and the same move again): it says what that one said — the same tread of
    the same face — so it is not folded in again; counted twice, one piece of evidence
    would make the belief over-sure (σ_x 10 → 2.7 cm over five contacts at one spot on
    the tank)."""

    def __init__(self, cfg: ContactFixConfig | None = None, apart_m: float = 0.15) -> None:
        self.cfg = cfg or ContactFixConfig()
        self.apart_m = apart_m
        self.repeats = 0  # contacts at the last fix's place, not folded in
        self._last: tuple[float, float] | None = None

    def on_contact(self, ekf: WallEkf, depth: Depth) -> ContactFix:
        x, y, _ = ekf.pose
        if self._last is not None and math.hypot(x - self._last[0],
                                                 y - self._last[1]) < self.apart_m:
            self.repeats += 1
            return ContactFix(False, "the place of the last fix")
        fix = contact_fix(ekf, depth, self.cfg)
        if fix.fixed:
            x1, y1, _ = ekf.pose
            self._last = (x1, y1)
        return fix
