"""The three scenes of seed 004 §3.2 (Figs. 10–11) and a closed-loop run of
a TEB planner on the 4WS base through them.

Scenes (0.05 m cells, x along columns, y along rows):

- ``obstacle_at_goal``: a box stands just in front of the goal (Fig. 10);
- ``l_dead_end``: the robot starts in an L-shaped dead end facing its closed
  end, with the goal behind it (Fig. 11, the L region);
- ``narrow_corridor``: a 1.2 m corridor with a right-angle bend, the robot
  starting 60° off its axis (Fig. 11, the narrow passage).

:func:`run_scene` plans the global path with :func:`any_angle` on the map
inflated by the clearance, smooths it (:func:`smooth_path`), and then runs
TEB cycles every ``dt_s``: local goal 2.5 m along the path, one
:meth:`Teb.plan_step`, the command applied through the 4WS pose update
(:func:`integrate_pose`). It reports whether the goal was reached, the
distance driven in reverse, the closest approach to an obstacle and the
plan-step CPU times.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..kinematics import integrate_pose
from .optimised_astar import any_angle, smooth_path
from .teb import ObstacleField, Teb, TebConfig

RES_M = 0.05
SCENES = ("obstacle_at_goal", "l_dead_end", "narrow_corridor")


@dataclass
class Scene:
    name: str
    blocked: np.ndarray
    start: tuple[float, float, float]
    goal: tuple[float, float, float]


def _cells(x0, y0, x1, y1):
    def k(v):
        return int(round(v / RES_M))

    return slice(k(y0), k(y1)), slice(k(x0), k(x1))


def _box(g, x0, y0, x1, y1):
    g[_cells(x0, y0, x1, y1)] = True


def make_scene(name: str) -> Scene:
    if name == "obstacle_at_goal":
        g = np.zeros((120, 200), dtype=bool)
        _box(g, 6.4, 2.0, 7.1, 4.0)
        return Scene(name, g, (1.0, 3.0, 0.0), (8.0, 3.0, 0.0))
    if name == "l_dead_end":
        g = np.zeros((160, 200), dtype=bool)
        _box(g, 3.0, 2.6, 8.0, 2.8)  # lower wall of the pocket
        _box(g, 3.0, 5.2, 6.0, 5.4)  # upper wall up to the leg
        _box(g, 7.8, 2.6, 8.0, 7.6)  # closed end, right
        _box(g, 5.8, 5.2, 6.0, 7.6)  # the leg's left wall
        _box(g, 5.8, 7.4, 8.0, 7.6)  # the leg's closed top
        return Scene(name, g, (6.6, 4.0, 0.0), (1.0, 4.0, math.pi))
    if name == "narrow_corridor":
        g = np.ones((160, 160), dtype=bool)
        _box_free(g, 0.4, 1.0, 6.2, 2.2)  # the corridor, 1.2 m wide
        _box_free(g, 5.0, 1.0, 6.2, 7.6)  # after the bend
        return Scene(name, g, (1.0, 1.6, math.radians(60)), (5.6, 7.0, math.pi / 2))
    raise ValueError(f"unknown scene {name!r}; scenes: {', '.join(SCENES)}")


def _box_free(g, x0, y0, x1, y1):
    g[_cells(x0, y0, x1, y1)] = False


@dataclass
class RunResult:
    scene: str
    optimised: bool
    reached: bool
    time_s: float
    reverse_m: float
    min_clearance_m: float
    turns_in_place: int
    band_min_speed_mps: float = math.inf  # the most negative planned speed
    step_cpu_ms: list[float] = field(default_factory=list)
    poses: list[tuple[float, float, float]] = field(default_factory=list)
    band_sizes: list[int] = field(default_factory=list)

    @property
    def outcome(self) -> str:
        if self.reached:
            return "reached"
        return "stalled"


def global_path(scene: Scene, clearance_m: float) -> np.ndarray:
    """Smoothed any-angle path in metres (x, y) from start to goal."""
    k = int(math.ceil(clearance_m / RES_M))
    infl = _inflate(scene.blocked, k)
    s = (int(scene.start[1] / RES_M), int(scene.start[0] / RES_M))
    t = (int(scene.goal[1] / RES_M), int(scene.goal[0] / RES_M))
    infl[s] = infl[t] = False
    res = any_angle(infl, s, t)
    if not res.found:
        raise ValueError(f"scene {scene.name}: no global path")
    curve = smooth_path(scene.blocked, res.points, safety_cells=k - 1, step=2.0)
    return curve[:, ::-1] * RES_M  # (row, col) cells -> (x, y) metres


def _inflate(blocked: np.ndarray, k: int) -> np.ndarray:
    from scipy import ndimage

    return ndimage.distance_transform_edt(~blocked) <= k


def local_goal(path: np.ndarray, xy, ahead_m: float, final_heading: float):
    """The point ``ahead_m`` along the path past the point nearest to xy, its
    heading, and the path piece up to it."""
    k = int(np.argmin(np.linalg.norm(path - np.asarray(xy), axis=1)))
    seg = np.linalg.norm(np.diff(path[k:], axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    if s[-1] <= ahead_m:
        return np.array([*path[-1], final_heading]), path[k:]
    j = int(np.searchsorted(s, ahead_m))
    d = path[k + j] - path[k + j - 1]
    return np.array([*path[k + j], math.atan2(d[1], d[0])]), path[k:k + j + 1]


def band_min_speed(step) -> float:
    """The lowest signed speed along the band (negative: a reverse step)."""
    p = step.poses
    d = np.diff(p[:, :2], axis=0)
    v = (np.cos(p[:-1, 2]) * d[:, 0] + np.sin(p[:-1, 2]) * d[:, 1]) / step.dts
    return float(np.min(v))


def run_scene(name: str, optimised: bool, dt_s: float = 0.1, max_time_s: float = 40.0,
              config: TebConfig | None = None, record: bool = False) -> RunResult:
    scene = make_scene(name)
    cfg = config or TebConfig(optimised=optimised)
    teb = Teb(cfg)
    fld = ObstacleField(scene.blocked, RES_M)
    path = global_path(scene, cfg.clearance_m)
    pose = scene.start
    v = 0.0
    out = RunResult(name, optimised, False, 0.0, 0.0, math.inf, 0)
    t = 0.0
    first = True
    while t < max_time_s:
        xy = np.array(pose[:2])
        if np.linalg.norm(xy - np.array(scene.goal[:2])) < 0.15:
            out.reached = True
            break
        lg, piece = local_goal(path, xy, 2.5, scene.goal[2])
        to_goal = np.array(scene.goal[:2]) - xy
        if np.linalg.norm(to_goal) < 1.0:
            # Final approach: position only (the arc model cannot close a
            # sideways offset shorter than the turning radius).
            lg = np.array([*scene.goal[:2], math.atan2(to_goal[1], to_goal[0])])
            piece = np.vstack([xy, scene.goal[:2]])
        c0 = time.process_time()
        step = teb.plan_step(pose, lg, piece, fld, v, path_is_new=first)
        out.step_cpu_ms.append((time.process_time() - c0) * 1e3)
        out.band_sizes.append(len(step.poses))
        if not step.turning_in_place:
            out.band_min_speed_mps = min(out.band_min_speed_mps, band_min_speed(step))
        first = False
        tw = step.twist
        out.turns_in_place += int(step.turning_in_place)
        if tw.vx < -1e-6:
            out.reverse_m += -tw.vx * dt_s
        pose = integrate_pose(pose, tw, dt_s)
        v = tw.vx
        out.min_clearance_m = min(out.min_clearance_m, float(fld.distance(np.array(pose[:2]))))
        if record:
            out.poses.append(pose)
        t += dt_s
    out.time_s = t
    return out
