"""A headless inspection of a tank wall: plan the coverage (seed 001), drive
the climber's probe over every planned cell, read the thickness, and report
coverage and the thinnest spot.

The probe sits at the body's front face (seed 001 Fig. 2, n = 0), l = L/2
ahead of the wheel axle midpoint. Steering that point instead of the axle
makes the differential drive exactly invertible (feedback linearisation):

    [ẋ_P, ẏ_P] = R(θ)·[v, l·ω]  ⇒  v = u·(cos θ, sin θ),  ω = u·(−sin θ, cos θ)/l

for a wanted probe velocity u pointing at the next cell centre. This first
version steers on the true pose; the climber's localisation (encoders + IMU
through the EKF of app/core/localisation, seed 003 §2.2) replaces it when
that filter lands. Slip therefore only slows the run here.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np

from app.core.planner.coverage import plan_coverage

from .kinematics import ClimberBody, ClimberParams, ClimberState
from .wall_world import WallWorld

log = logging.getLogger(__name__)


@dataclass
class InspectionResult:
    planned: int  # reachable cells the plan visits
    probed: int  # of those, cells the probe read
    measured: np.ndarray = field(repr=False)  # mm, NaN where not read
    sim_time_s: float = 0.0
    thinnest_mm: float = math.nan
    thinnest_cell: tuple[int, int] | None = None

    @property
    def coverage(self) -> float:
        return self.probed / self.planned if self.planned else 1.0


def _probe_point(s: ClimberState, lead_m: float) -> tuple[float, float]:
    return s.x_m + lead_m * math.cos(s.theta_rad), s.y_m + lead_m * math.sin(s.theta_rad)


def inspect_wall(
    world: WallWorld,
    start: tuple[int, int],
    params: ClimberParams | None = None,
    dt_s: float = 0.05,
    gain: float = 2.0,
    reach_m: float = 0.02,
    seed: int = 0,
    max_steps_per_cell: int = 400,
) -> InspectionResult:
    """Cover the wall from ``start`` (row, col of the probe) and probe it."""
    params = params or ClimberParams()
    lead = params.length_m / 2
    plan = plan_coverage(world.blocked, start, wrap=True)
    x0, y0 = world.cell_centre(*start)
    body = ClimberBody(params, ClimberState(x0 - lead, y0, 0.0), world.circ_m, seed=seed)
    measured = np.full(world.blocked.shape, np.nan)
    sim_t = 0.0
    for target in plan.cells:
        tx, ty = world.cell_centre(*target)
        for _ in range(max_steps_per_cell):
            px, py = _probe_point(body.s, lead)
            ex, ey = world.wrap_dx(tx - px), ty - py
            if math.hypot(ex, ey) < reach_m:
                break
            ux, uy = gain * ex, gain * ey
            speed = math.hypot(ux, uy)
            if speed > params.v_max_mps:
                ux, uy = ux * params.v_max_mps / speed, uy * params.v_max_mps / speed
            c, s = math.cos(body.s.theta_rad), math.sin(body.s.theta_rad)
            body.step(ux * c + uy * s, (-ux * s + uy * c) / lead, dt_s)
            sim_t += dt_s
            px, py = _probe_point(body.s, lead)
            cell = world.cell_of(px, py)
            if cell is not None and math.isnan(measured[cell]):
                reading = world.probe(px, py)
                if reading is not None:
                    measured[cell] = reading
        else:
            log.warning("probe did not reach cell %s", target)
    planned = len(set(plan.cells))
    probed = int(sum(1 for p in set(plan.cells) if not math.isnan(measured[p])))
    res = InspectionResult(planned, probed, measured, sim_t)
    if probed:
        i = np.unravel_index(int(np.nanargmin(measured)), measured.shape)
        res.thinnest_mm = float(measured[i])
        res.thinnest_cell = (int(i[0]), int(i[1]))
    return res
