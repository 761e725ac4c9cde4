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
   body stops at the first overlap); when the caller tells which way the body
   was driving (``moving``: +1 forward, −1 back), only those a step further
   that way would press deeper: a body backing away from a manhole above it
   cannot have stopped against it, nor one climbing straight up against a
   vertical face beside it;
2. when there are none, or the nearest is more than ``surprise`` σ from the
   belief, the belief hardly explains the contact: it is over-sure or off
   (a belief 10 cm off in x and sure of it to 2 cm would otherwise take a
   contact with the band's lower side as a y error), and its x and y variances are opened to
   at least ``floor_sigma_m`` and ``floor_sigma_y_m`` and the search made
   again;
3. they are weighted by the belief's Gaussian; when they fall apart into more
   than one connected piece of weight (two faces at once: the bottom edge and
   a nozzle) the contact is ambiguous and nothing is fixed (the touching poses
   not driven into join pieces with no weight of their own: a staircase's risers
   its treads, which alone fell apart one piece a tread);
4. else the belief is moved to the **mode**, the touching pose nearest it in its
   own metric (the estimate projected onto the constraint, as in the constrained
   Kalman filter's estimate projection, Simon & Chia 2002), with the touching
   poses' weighted second moment about it as its covariance (their spread about
   their mean, and that mean's distance from the mode); one two-dimensional
   update on x and y brings the filter's marginal there (the measurement's noise is
   (C⁻¹ − P⁻¹)⁻¹, the information the contact adds; a direction it adds none to
   gets none), so the correlated states (the slip, the accelerometer's bias)
   follow as they do for a landmark;
5. when still no grid pose touches, the contact is not explained by the
   belief (something not on the map, a heading far off) and is not used.

Why the mode and not the weighted mean of the touching poses (the conditional
mean, used before). The moves keep the believed footprint clear of the map, so
the body meets an obstacle only where the belief stands on its clear side: the
belief's lane is beyond the tread's corner (a stair climbed into) or beside the
face, and the truth, its real error away, sits on the touching set's end nearest
the belief. The mode moves the belief from the clear side onto that set, toward
the truth and never past it while the truth lies on that piece; the mean is that
only when the belief's σ is its real error. Logged through the link on the tank
(``bench/contact_fix_replay.py``): σ_x 8–12 cm in the stair band where the real
error was 1–4 cm, and the mean of a 10–18 cm tread moved x 6–10 cm the wrong way
in eight of the first ten large fixes; beside a manhole a vertical side face's
mean lay 0.8 σ_y above the belief along the face and moved y 13 cm up, 9 cm past
the truth. The mode was within 2.3 cm on all of them.

A belief can be off by more than any of this: after ``ContactFixes.wide_after``
contacts in a row at one believed place that the belief did not explain (nothing
touching within its σ), the search is made once more with x and y opened to
``wide_sigma_m`` (a tank run pressed 900 times against the shell's bottom edge
with the belief 0.2 m higher, beside a manhole); that fix is made only if it is
unambiguous, as every other.

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
    estimate: str = "mode"  # the fix's point: "mode" (step 4) or "mean" (the weighted mean,
    # before: kept for bench/contact_fix_replay.py's comparison)
    into_frac: float = 0.25  # moving: a step further must press this share of a step deeper
    wide_sigma_m: float = 0.1  # the widened search (ContactFixes): x and y σ opened to this


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


def _touching(ekf: WallEkf, depth: Depth, cfg: ContactFixConfig, moving: float,
              p: np.ndarray) -> tuple[float, list, list]:
    """The grid's step and the (i, j) grid poses about the belief within the search
    window (of the (x, y) covariance ``p``) whose footprint touches the map (within
    half a step: the body stops at the first overlap, to a hundredth of a mm in the
    simulator) and, when ``moving`` is ±1, would press deeper a step further that
    way (step 1); and the touching poses that would not (they join the pieces of one
    face: the risers between a staircase's treads)."""
    x0, y0, th = ekf.pose
    sx, sy = (math.sqrt(max(0.0, p[k, k])) for k in (0, 1))
    grid = min(cfg.grid_m, max(cfg.min_grid_m, min(sx, sy) / 2))
    ni, nj = (max(2, math.ceil(min(cfg.max_half_m, cfg.window * s) / grid)) for s in (sx, sy))
    ux, uy = moving * grid * math.cos(th), moving * grid * math.sin(th)
    cells, joins = [], []
    for j in range(-nj, nj + 1):
        for i in range(-ni, ni + 1):
            x, y = x0 + i * grid, y0 + j * grid
            d = depth(x, y, th, grid / 2)
            if d > 0.0 and depth(x, y, th, 0.0) <= grid / 2:
                if not moving or depth(x + ux, y + uy, th, grid / 2) > d + cfg.into_frac * grid:
                    cells.append((i, j))
                else:
                    joins.append((i, j))
    return grid, cells, joins


def _out_of_the_map(depth: Depth, pose: tuple[float, float, float], point: np.ndarray,
                    grid: float) -> np.ndarray:
    """``point`` (an offset from ``pose``), a grid pose that may overlap the map by up to
    half a step, moved on along its direction from the belief to where its footprint
    just clears the map (at most a step on): the body cannot stand in the map, and a
    belief in it by a few mm turned the relay's recoil the wrong way."""
    x0, y0, th = pose
    n = math.hypot(*point)
    if n == 0.0 or depth(x0 + point[0], y0 + point[1], th, 0.0) <= 0.0:
        return point
    u = point / n
    if depth(x0 + point[0] + grid * u[0], y0 + point[1] + grid * u[1], th, 0.0) > 0.0:
        return point  # not out within a step: left as it is
    lo, hi = 0.0, grid
    for _ in range(8):
        t = (lo + hi) / 2
        lo, hi = (t, hi) if depth(x0 + point[0] + t * u[0], y0 + point[1] + t * u[1], th,
                                  0.0) > 0.0 else (lo, t)
    return point + hi * u


def _surprise(p: np.ndarray, grid: float, cells: list) -> float:
    """How many of the belief's σ the nearest touching pose is from it (inf: none)."""
    if not cells:
        return math.inf
    q = np.asarray(cells) * grid
    return math.sqrt(float(np.einsum("ij,jk,ik->i", q, np.linalg.inv(p), q).min()))


def _xy(ekf: WallEkf) -> np.ndarray:
    return ekf.covariance[np.ix_((X, Y), (X, Y))].copy()


def _widened(p: np.ndarray, sx: float, sy: float) -> np.ndarray:
    """``p`` with its x and y σ raised to at least ``sx`` and ``sy``, the correlation
    kept (as ``WallEkf.open_variance`` does)."""
    f = np.array([max(1.0, s / math.sqrt(v)) if v > 0.0 else 1.0
                  for s, v in ((sx, p[0, 0]), (sy, p[1, 1]))])
    out = p * np.outer(f, f)
    for k, s in enumerate((sx, sy)):
        out[k, k] = max(out[k, k], s * s)
    return out


def contact_fix(ekf: WallEkf, depth: Depth, cfg: ContactFixConfig | None = None,
                moving: float = 0.0, wide: bool = False) -> ContactFix:
    """The body stopped against the map (the board's contact flag): fold that
    into ``ekf`` as above. ``depth(x, y, θ, grow)``: how far the footprint at
    that pose, grown by ``grow`` on every side, reaches into the map's edges or
    obstacles (≤ 0 clear; a clear footprint's distance need not be told).
    ``moving``: the sign of the speed last commanded along the heading (0: not
    known, or a turn in place). ``wide``: the search of a belief that did not
    explain the contacts before it (``ContactFixes``), x and y opened to
    ``wide_sigma_m``; the filter's covariance is opened only if a fix is made."""
    cfg = cfg or ContactFixConfig()
    moving = float(np.sign(moving))
    x0, y0, th = ekf.pose
    p = _xy(ekf)
    if wide:
        p = _widened(p, cfg.wide_sigma_m, cfg.wide_sigma_m)
    grid, cells, joins = _touching(ekf, depth, cfg, moving, p)
    if not wide and _surprise(p, grid, cells) > cfg.surprise:  # over-sure, or off
        ekf.open_variance(X, cfg.floor_sigma_m)
        ekf.open_variance(Y, cfg.floor_sigma_y_m)
        p = _xy(ekf)
        grid, cells, joins = _touching(ekf, depth, cfg, moving, p)
    if not cells:
        return ContactFix(False, "no pose near the belief touches the map")
    c = np.asarray(cells)
    q = c * grid
    pinv = np.linalg.inv(p)
    m2 = np.einsum("ij,jk,ik->i", q, pinv, q)
    w = np.exp(-0.5 * (m2 - m2.min()))
    w /= w.sum()
    # pieces of weight, joined through the touching poses not driven into (weight 0)
    pieces = _pieces(np.vstack([c, np.asarray(joins, int).reshape(-1, 2)]),
                     np.concatenate([w, np.zeros(len(joins))]))
    if len(pieces) > 1 and pieces[1] >= cfg.min_share:
        return ContactFix(False, f"ambiguous ({len(pieces)} pieces)", len(cells))
    # the fix's point (step 4): the mode, the touching pose nearest the belief (moved on
    # out of the map where it overlaps it), and the touching poses' weighted second
    # moment about it (their spread, and how far their mean lies from it: the truth is
    # on the far side of the mode, not about it)
    if cfg.estimate == "mode":
        point = _out_of_the_map(depth, (x0, y0, th), q[int(np.argmin(m2))], grid)
    else:
        point = w @ q
    dq = q - point
    cov = (dq * w[:, None]).T @ dq + np.eye(2) * grid**2 / 12
    if math.hypot(*point) > cfg.max_move_m:
        return ContactFix(False, "too far from the belief", len(cells))
    if wide:  # the belief opened as the search was (a fix is made)
        ekf.open_variance(X, math.sqrt(p[0, 0]))
        ekf.open_variance(Y, math.sqrt(p[1, 1]))
        pinv = np.linalg.inv(_xy(ekf))
    # the contact's information, C⁻¹ − P⁻¹, as a measurement of (x, y) with noise R
    vals, vecs = np.linalg.eigh(np.linalg.inv(cov) - pinv)
    vals = np.maximum(vals, 1e-4)  # a direction the contact tells nothing of: R of 100 m
    r = vecs @ np.diag(1.0 / vals) @ vecs.T
    # the measurement z whose update moves the (x, y) marginal's mean by ``point``
    z_off = (np.eye(2) + r @ pinv) @ point
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
    the tank).

    Contacts the belief does not explain (no touching pose within its σ), ``wide_after``
    of them in a row within ``apart_m`` of one believed place, are a belief off by more
    than it knows: the last of them is searched again with x and y opened to
    ``ContactFixConfig.wide_sigma_m`` (``contact_fix(wide=True)``), and fixed only if
    that explanation is unambiguous; else the count starts again (each widened search
    is one more contact's evidence, never a jump to the nearer of two faces)."""

    def __init__(self, cfg: ContactFixConfig | None = None, apart_m: float = 0.15,
                 wide_after: int = 3) -> None:
        self.cfg = cfg or ContactFixConfig()
        self.apart_m = apart_m
        self.wide_after = wide_after
        self.repeats = 0  # contacts at the last fix's place, not folded in
        self.widened = 0  # widened searches made ...
        self.widened_fixed = 0  # ... and the fixes they made
        self._last: tuple[float, float] | None = None
        self._unexplained: tuple[float, float] | None = None  # where a run of them began
        self._run = 0  # ... and its length

    def on_contact(self, ekf: WallEkf, depth: Depth, moving: float = 0.0) -> ContactFix:
        """``moving``: the sign of the speed last commanded (``contact_fix``)."""
        x, y, _ = ekf.pose
        if self._last is not None and math.hypot(x - self._last[0],
                                                 y - self._last[1]) < self.apart_m:
            self.repeats += 1
            return ContactFix(False, "the place of the last fix")
        fix = contact_fix(ekf, depth, self.cfg, moving)
        if not fix.fixed and fix.poses == 0:  # unexplained
            u = self._unexplained
            if u is None or math.hypot(x - u[0], y - u[1]) >= self.apart_m:
                self._unexplained, self._run = (x, y), 0
            self._run += 1
            if self._run >= self.wide_after:
                self._run = 0
                self.widened += 1
                fix = contact_fix(ekf, depth, self.cfg, moving, wide=True)
                self.widened_fixed += fix.fixed
        if fix.fixed:
            x1, y1, _ = ekf.pose
            self._last = (x1, y1)
            self._unexplained, self._run = None, 0
        return fix
