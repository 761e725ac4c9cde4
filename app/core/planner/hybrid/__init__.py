"""Global path plus local avoidance (seed 000 §4.2.5, Fig. 15): the
:class:`HybridPlanner` (planner.py, where the method is described), its settings
and modes (config.py), the global path (route.py), the safety governor
(governor.py) and the governor's rollout kernels (rollout.py)."""

from .config import (
    AVOIDING,
    BLOCKED,
    FOLLOWING,
    NO_PATH,
    REACHED,
    REJOINING,
    WALL_SLACK_M,
    HybridConfig,
)
from .planner import HybridPlanner
from .rollout import rollout_clearance, rollout_many, rollout_ramp

__all__ = [
    "AVOIDING",
    "BLOCKED",
    "FOLLOWING",
    "NO_PATH",
    "REACHED",
    "REJOINING",
    "WALL_SLACK_M",
    "HybridConfig",
    "HybridPlanner",
    "rollout_clearance",
    "rollout_many",
    "rollout_ramp",
]
