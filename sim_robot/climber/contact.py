"""The body's footprint against the wall: where the simulated crawler is
stopped (ground truth, for the simulator only; navigation never calls it).

The body is the 288 × 260 mm rectangle of seed 003 Table 1 about the axle's
midpoint (the pose of :class:`~.kinematics.ClimberBody`). It may not reach
below the shell's bottom (the floor's annular plate and the fillet weld) or
above its top, nor overlap a blocked cell of the wall's map (manholes,
nozzles, the stair band, seams it may not cross: the planner's raster,
app/core/planner/coverage/wall.py). :meth:`WallContact.depth` is how far
the footprint reaches into the nearest of them (separating axes, rectangle
against each blocked cell's square), :meth:`WallContact.touches` what it
touches. The body model (:meth:`ClimberBody.step`) takes a step only as far
as it stays out of them, and counts the contacts.
"""

from __future__ import annotations

import math

import numpy as np

from app.core.planner.coverage.wall import WallSpec, rasterise

# names of what the body touched, as reported (records, relay events)
BOTTOM, TOP = "bottom edge", "top edge"
KINDS = ("manhole", "nozzle", "stair", "seam")
MAX_MARGIN_M = 0.1  # the most a footprint may be grown by (touches(margin_m=...))


def _kinds(spec: WallSpec) -> np.ndarray:
    """Each cell's obstacle kind: 0 free, k + 1 for KINDS[k]."""
    parts = (dict(manholes=spec.manholes), dict(nozzles=spec.nozzles), dict(stairs=spec.stairs),
             dict(seams=tuple(b for b in spec.seams if not b.crossable)))
    out = np.zeros(spec.shape, np.int8)
    for k, part in enumerate(parts):
        mask = rasterise(WallSpec(spec.diameter_m, spec.height_m, spec.cell_m, **part))
        out[mask & (out == 0)] = k + 1
    return out


class WallContact:
    """Footprint checks on one wall for a body ``length_m`` × ``width_m``."""

    def __init__(self, spec: WallSpec, blocked: np.ndarray, length_m: float,
                 width_m: float) -> None:
        self.height_m = spec.height_m
        self.cell_m = spec.cell_m
        self.blocked = np.asarray(blocked, bool)
        self.rows, self.cols = self.blocked.shape
        self.circ_m = self.cols * self.cell_m
        self.a, self.b = length_m / 2, width_m / 2
        self.reach_m = math.hypot(self.a, self.b)  # the footprint's half-diagonal
        self.kind = _kinds(spec)
        self.kind[self.blocked & (self.kind == 0)] = 1  # (a blocked cell of no known kind)
        # cells whose centre is near enough an obstacle for the footprint (grown by up to
        # MAX_MARGIN_M) round a body centred anywhere in them to reach it (Chebyshev
        # distance in cells): elsewhere only the edges need checking
        k = math.ceil((self.reach_m + MAX_MARGIN_M) / self.cell_m) + 1
        near = self.blocked.copy()
        for _ in range(k):
            grown = near.copy()
            grown[1:] |= near[:-1]
            grown[:-1] |= near[1:]
            near = grown | np.roll(grown, 1, axis=1) | np.roll(grown, -1, axis=1)
        self.near = near

    def _edge_depth(self, y: float, theta: float, grow: float) -> tuple[float, str]:
        ext = (self.a + grow) * abs(math.sin(theta)) + (self.b + grow) * abs(math.cos(theta))
        below, above = ext - y, y + ext - self.height_m
        return (below, BOTTOM) if below >= above else (above, TOP)

    def obstacle_depth(self, x: float, y: float, theta: float,
                        grow: float) -> tuple[float, str]:
        """The deepest overlap with a blocked cell (≤ 0: none) and its kind."""
        d = self.cell_m
        r = math.floor(y / d)
        c = math.floor((x % self.circ_m) / d)
        if 0 <= r < self.rows and not self.near[r, c]:
            return -math.inf, ""
        a, b = self.a + grow, self.b + grow
        c_, s_ = math.cos(theta), math.sin(theta)
        ex = a * abs(c_) + b * abs(s_)
        ey = a * abs(s_) + b * abs(c_)
        r0, r1 = max(0, math.floor((y - ey) / d)), min(self.rows - 1, math.floor((y + ey) / d))
        if r1 < r0:
            return -math.inf, ""
        cols = np.arange(math.floor((x - ex) / d), math.floor((x + ex) / d) + 1)
        sub = self.blocked[r0:r1 + 1][:, cols % self.cols]
        if not sub.any():
            return -math.inf, ""
        rr, cc = np.nonzero(sub)
        # each blocked cell's centre relative to the body's centre (the nearest image
        # round the tank: cols are unwrapped about x)
        dx = (cols[cc] + 0.5) * d - x
        dy = (r0 + rr + 0.5) * d - y
        h = d / 2
        # separating axes: the wall's x and y, the body's u and v
        over = np.minimum(ex + h - np.abs(dx), ey + h - np.abs(dy))
        du, dv = dx * c_ + dy * s_, -dx * s_ + dy * c_
        sq = h * (abs(c_) + abs(s_))  # the square's half-extent along u (and v)
        over = np.minimum(over, np.minimum(a + sq - np.abs(du), b + sq - np.abs(dv)))
        i = int(np.argmax(over))
        kind = int(self.kind[r0 + rr[i], cols[cc[i]] % self.cols])
        return float(over[i]), KINDS[kind - 1]

    def depth(self, x: float, y: float, theta: float, grow_m: float = 0.0) -> tuple[float, str]:
        """How far (m) the footprint at (x, y, θ), grown by ``grow_m`` (at most
        MAX_MARGIN_M) on every side, reaches past the wall's top or bottom or into
        an obstacle, the deeper, and what that is; ≤ 0 when clear."""
        edge, what = self._edge_depth(y, theta, grow_m)
        obst, kind = self.obstacle_depth(x, y, theta, grow_m)
        return (obst, kind) if obst > edge else (edge, what)

    def touches(self, x: float, y: float, theta: float, margin_m: float = 0.0) -> str | None:
        """What the footprint, grown by ``margin_m``, overlaps; None when clear."""
        depth, what = self.depth(x, y, theta, margin_m)
        return what if depth > 1e-9 else None
