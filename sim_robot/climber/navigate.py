"""Going to a point on the wall: A* + DWA with seed 003's Table 3 limits
(§3.2, Figs. 5–7; the experiments of §4.2, Figs. 14–15).

The global path is the planner's A* on the wall grid inflated by the body's
radius; the local planner is its dynamic window (app/core/planner/dwa.py,
Table 3: v ≤ 0.15 m/s, |ω| ≤ 0.5 rad/s, 0.5 m/s², 3.5 rad/s², 10 × 10
samples), both driven through :class:`HybridPlanner`. The climber's body
(kinematics.py) executes the commands with its slip.

The experiment wall of §4.2: a steel mud tank face 2 m wide and 1.6 m high
with a pipe of 300 mm diameter joined to it (:func:`mud_tank_wall`). As in
inspection.py, this first version steers on the true pose; the EKF of
app/core/localisation takes over when it lands.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from app.core.planner import GridMap, HybridConfig, HybridPlanner
from app.core.planner.coverage.wall import Disc, WallSpec, rasterise

from .kinematics import ClimberBody, ClimberParams, ClimberState


def mud_tank_wall(pipe_xy_m: tuple[float, float] = (1.0, 0.8)) -> WallSpec:
    """§4.2's wall: 2 m × 1.6 m, a 300 mm pipe; D = 0.05 m for navigation."""
    return WallSpec(2.0 / math.pi, 1.6, 0.05, nozzles=(Disc(pipe_xy_m[0], pipe_xy_m[1], 0.3),))


@dataclass
class NavResult:
    reached: bool
    status: str
    time_s: float
    path_xy: list[tuple[float, float]]
    trajectory: list[tuple[float, float, float]] = field(repr=False)
    min_clearance_m: float = math.inf


def navigate(
    spec: WallSpec,
    start_xytheta: tuple[float, float, float],
    goal_xy: tuple[float, float],
    params: ClimberParams | None = None,
    dt_s: float = 0.1,
    max_time_s: float = 120.0,
    seed: int = 0,
) -> NavResult:
    """Drive from the start pose to the goal; the wall's edges are walls."""
    params = params or ClimberParams()
    radius = math.hypot(params.length_m, params.width_m) / 2
    grid = GridMap(rasterise(spec), spec.cell_m, (0.0, 0.0))
    cfg = HybridConfig(
        robot_radius_m=radius,
        inflation_margin_m=0.02,
        local_planner="dwa",
        global_planner="astar",
        goal_tolerance_m=0.05,
        lookahead_m=0.2,
        rejoin_ahead_m=0.4,
    )
    hp = HybridPlanner(grid, cfg)
    path = hp.plan(start_xytheta[:2], goal_xy)
    body = ClimberBody(params, ClimberState(*start_xytheta), seed=seed)
    traj = [start_xytheta]
    status, t = "no_path" if not path else "following", 0.0
    min_clear = math.inf
    while path and t < max_time_s:
        s = body.s
        v, w, status = hp.step((s.x_m, s.y_m, s.theta_rad), (s.v_mps, s.omega_rps), (), dt_s)
        if status in ("reached", "no_path", "blocked"):
            break
        body.step(v, w, dt_s)
        t += dt_s
        traj.append((body.s.x_m, body.s.y_m, body.s.theta_rad))
        r, c = grid.world_to_cell(body.s.x_m, body.s.y_m)
        if grid.in_bounds(r, c):
            min_clear = min(min_clear, float(grid.distance_m[r, c]))
    return NavResult(status == "reached", status, t, path, traj, min_clear)
