"""Path planners for the patrol robot (Qt-free).

Global: :func:`astar`, :func:`jps` on a :class:`GridMap`; any-angle
shortening and smoothing in :mod:`anyangle`; the optimised A* of seed 004
(:func:`any_angle` on cell-edge nodes, :func:`smooth_path`) in
:mod:`optimised_astar`. Local: improved artificial
potential field (:mod:`apf`) and dynamic window approach (:mod:`dwa`);
:class:`HybridPlanner` joins them (seed 000, Fig. 15). Complete coverage of
the tank wall: :func:`coverage_path` (seed 001, package :mod:`coverage`).
"""

from ._result import PlanResult
from .apf import APFConfig, PotentialField
from .astar import astar
from .coverage import coverage_path
from .dwa import DWAConfig, DynamicWindow, Kinematics
from .grid import GridMap, load_movingai_map, load_movingai_scen, load_ros_map, save_ros_map
from .hybrid import HybridConfig, HybridPlanner
from .jps import JpsMap, JumpTable, jps
from .optimised_astar import AnyAngleResult, any_angle, smooth_path

__all__ = [
    "APFConfig",
    "AnyAngleResult",
    "DWAConfig",
    "DynamicWindow",
    "GridMap",
    "HybridConfig",
    "HybridPlanner",
    "JpsMap",
    "JumpTable",
    "Kinematics",
    "PlanResult",
    "PotentialField",
    "any_angle",
    "astar",
    "coverage_path",
    "jps",
    "load_movingai_map",
    "load_movingai_scen",
    "load_ros_map",
    "save_ros_map",
    "smooth_path",
]
