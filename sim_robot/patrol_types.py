"""The mission executor's states, configuration and bookkeeping records
(:mod:`sim_robot.patrol` drives them)."""

from __future__ import annotations

import math
from dataclasses import dataclass

IDLE, PLANNING, DRIVING, AVOIDING, INSPECTING = "idle", "planning", "driving", "avoiding", \
    "inspecting"
PAUSED, DOCKING, DONE, ABORTED, FAILED = "paused", "docking", "done", "aborted", "failed"
ACTIVE = (PLANNING, DRIVING, AVOIDING, INSPECTING, DOCKING)
MAX_PATH_POINTS = 2000


@dataclass
class PatrolConfig:
    control_dt_s: float = 0.1  # sim time per control step
    robot_radius_m: float = 0.35
    inflation_margin_m: float = 0.1
    local_planner: str = "apf"
    v_max_mps: float = 0.6
    v_min_mps: float = -0.2  # the safety governor may back away (a cornered robot)
    omega_max_rps: float = 1.0
    accel_mps2: float = 0.5  # below the MCU's 0.8, so the MCU follows
    alpha_rps2: float = 2.0
    detect_range_m: float = 3.5
    # a person standing may set off: the planner's safety check grows his
    # predicted disc at this rate (m/s) up to the cap (m); 0 = constant velocity
    slow_grow_mps: float = 1.0
    slow_grow_cap_m: float = 1.5
    # ... and a walking one's at this rate (his heading and speed are estimates)
    moving_grow_mps: float = 0.2
    goal_tolerance_m: float = 0.12
    face_tolerance_rad: float = 0.05
    face_timeout_s: float = 20.0
    stuck_s: float = 25.0
    progress_m: float = 0.3
    max_stuck_replans: int = 3
    max_recoveries: int = 3  # backing away from a touched obstacle, per leg
    no_path_retry_s: float = 2.0
    no_path_retries: int = 5
    local_horizon_s: float = 3.0
    # the camera streams in wall time: a meter needs this long in view for the desk to
    # read and fuse several frames, however fast the simulation runs
    inspect_min_wall_s: float = 2.5


@dataclass
class Target:
    name: str
    kind: str
    x: float
    y: float
    gauge: str | None = None
    dwell_s: float = 0.0
    heading: float | None = None
    point_index: int | None = None  # index in the route's points; None for the dock leg
    dock: bool = False


@dataclass
class Mission:
    route: str
    points: list[dict]  # status dicts (name, kind, x_m, y_m, gauge, state)
    targets: list[Target]
    started_t: float = 0.0


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


@dataclass
class PatrolStats:
    avoid_episodes: int = 0
    plans: int = 0
    path_length_m: float = 0.0  # sum of the global plans (replans included)
    driven_m: float = 0.0  # distance driven (measured speed x time) while on a mission
    skipped: int = 0
    recoveries: int = 0
