"""The magnetic wall climber of the tank-wall inspection (seeds 001, 003):
its body and slip (:mod:`kinematics`) and the wall it crawls on
(:mod:`wall_world`). Localisation uses the EKF of app/core/localisation
once it lands; the relay, MCU model and link are shared with the patrol
robot and not wired here yet.
"""

from .kinematics import ClimberBody, ClimberParams, ClimberState
from .wall_world import Patch, WallWorld

__all__ = ["ClimberBody", "ClimberParams", "ClimberState", "Patch", "WallWorld"]
