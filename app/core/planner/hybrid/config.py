"""The hybrid planner's settings (:class:`HybridConfig`) and the modes its
:meth:`~app.core.planner.hybrid.HybridPlanner.step` reports."""

from __future__ import annotations

from dataclasses import dataclass, field

from ..apf import APFConfig
from ..dwa import DWAConfig, Kinematics

FOLLOWING = "following"
AVOIDING = "avoiding"
REJOINING = "rejoining"
REACHED = "reached"
BLOCKED = "blocked"
NO_PATH = "no_path"
WALL_SLACK_M = 1e-3  # a robot touching a wall by the map may not go deeper than this


@dataclass
class HybridConfig:
    robot_radius_m: float = 0.25
    inflation_margin_m: float = 0.1
    local_planner: str = "apf"  # "apf" | "dwa"
    global_planner: str = "jps"  # "jps" | "astar"
    smooth: bool = True
    detect_range_m: float = 2.5  # surface distance that starts local avoidance
    close_range_m: float = 0.6  # any moving obstacle this close is avoided
    threat_gap_m: float = 0.5  # predicted closest approach that counts as a threat
    threat_horizon_s: float = 20.0
    clear_time_s: float = 1.0  # obstacle-free time before rejoining
    replan_on_rejoin: bool = True  # rejoin by replanning from where the robot is
    stall_time_s: float = 8.0  # no progress along the path this long: replan
    avoid_replan_s: float = 10.0  # avoiding this long without progress: replan around obstacles
    obstacle_sweep_s: float = 3.0  # a replan around obstacles blocks their next seconds
    replan_window_m: float = 5.0  # ... and searches only this far around start and goal
    lookahead_m: float = 0.4
    rejoin_ahead_m: float = 1.5  # local goal: this far along the path past the robot
    goal_tolerance_m: float = 0.1
    heading_gain: float = 1.5
    safety_horizon_s: float = 5.0
    safety_margin_m: float = 0.03
    dwa_yield_margin_m: float = 0.15  # the governor's margin for DWA arcs
    # Passive safety: a command is kept only if, held for commit_s and then
    # braked to rest at the limits, the robot would stand clear of every
    # predicted obstacle for the rest of the safety horizon (0 turns it off).
    commit_s: float = 0.3
    # The governor's prediction of a slow moving obstacle (a person standing
    # may set off): its disc grows at slow_grow_mps (standing; less the
    # faster it goes, none from slow_below_mps) up to slow_grow_cap_m more.
    slow_grow_mps: float = 0.0
    slow_grow_cap_m: float = 0.0
    slow_below_mps: float = 0.5
    # ... and a moving one's at moving_grow_mps (its heading and speed are
    # estimates), up to the same cap.
    moving_grow_mps: float = 0.0
    kin: Kinematics = field(default_factory=Kinematics)
    apf: APFConfig = field(default_factory=APFConfig)
    dwa: DWAConfig = field(default_factory=DWAConfig)
