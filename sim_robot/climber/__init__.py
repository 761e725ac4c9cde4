"""The magnetic wall climber of the tank-wall inspection (seeds 001, 003):
its body and slip (:mod:`kinematics`), the wall it crawls on
(:mod:`wall_world`), its accelerometer (:mod:`accelerometer`), MCU model,
relay and inspection mission (docs/climber.md). The relay localises it with
the wall EKF of app/core/localisation/wall_ekf.py.
"""

from .kinematics import ClimberBody, ClimberParams, ClimberState
from .wall_world import Patch, WallWorld

__all__ = ["ClimberBody", "ClimberParams", "ClimberState", "Patch", "WallWorld"]
