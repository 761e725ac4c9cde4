"""Kinematics of the robot bases (Qt-free).

:mod:`fws` — the four-wheel independent-steering base of seed 004 (§2.1,
Figs. 1–3): bicycle model with front and rear steering, the instantaneous
centre of rotation, the four wheels' angles and speeds, limits, modes and the
discrete pose update.
"""

from .fws import (
    FwsGeometry,
    Mode,
    Twist,
    WheelCommand,
    bicycle_to_twist,
    body_twist,
    icr,
    integrate_pose,
    limit_twist,
    min_turn_radius,
    mode_twist,
    realise,
    select_mode,
    twist_to_bicycle,
    wheel_commands,
)

__all__ = [
    "FwsGeometry",
    "Mode",
    "Twist",
    "WheelCommand",
    "bicycle_to_twist",
    "body_twist",
    "icr",
    "integrate_pose",
    "limit_twist",
    "min_turn_radius",
    "mode_twist",
    "realise",
    "select_mode",
    "twist_to_bicycle",
    "wheel_commands",
]
