"""Turning the crawler in place, to a heading of its estimate, and where a
route's lane changes call for it.

With the wheels turning opposite ways and the body not moving forward, the
wheels' along-track slip (which the filter knows only as learnt coefficients,
seed 003) cannot move the body: only the turn's own slip acts, and the gyro
sees it. Used at a lane's end and along a detour's legs, by the headless
inspection (:mod:`.inspection`, a blocking :func:`turn_to`) and by the relay's
executor (:mod:`.executor`, one :func:`turn_rate` per control period), and
between the accelerometer's standstills (:mod:`.accel_stops`).

The lane change (:func:`lane_change_turns`): at a lane's end the crawler turns
to face along the wall's horizontal, steps the one cell sideways there, where
the along-track slip is nil (it goes with |sin θ|), and turns to face the new
lane (docs/climber.md, "Turning in place at a lane's end")."""

from __future__ import annotations

import math
from collections.abc import Callable

TURN_RPS = 0.3  # the turns' yaw rate
TURN_TOL_RAD = math.radians(0.5)  # a turn ends this close to its heading
TURN_TIMEOUT_S = 60.0  # a turn that takes longer than this is given up

Cell = tuple[int, int]


def turn_rate(heading_now: float, heading: float) -> float | None:
    """The yaw rate of one control step of a turn in place the short way to
    ``heading`` (rad); None once within :data:`TURN_TOL_RAD` of it."""
    left = (heading - heading_now + math.pi) % (2 * math.pi) - math.pi
    if abs(left) < TURN_TOL_RAD:
        return None
    return math.copysign(min(TURN_RPS, 2.0 * abs(left)), left)


def turn_to(move: Callable[[float, float], None], heading_now: Callable[[], float],
            dt_s: float, heading: float) -> bool:
    """Turn in place the short way to ``heading`` (rad, as ``heading_now()``
    reports it); ``move(v, w)`` runs one control step. Whether it got there."""
    for _ in range(int(TURN_TIMEOUT_S / dt_s)):
        w = turn_rate(heading_now(), heading)
        if w is None:
            return True
        move(0.0, w)
    return False


def sideways(prev: Cell | None, cell: Cell, cols: int) -> int:
    """+1 (or −1) when ``cell`` is the next (previous) column's cell of ``prev``'s
    row, round the wall's seam; else 0."""
    if prev is None or prev[0] != cell[0]:
        return 0
    dc = (cell[1] - prev[1]) % cols
    return 1 if dc == 1 else -1 if dc == cols - 1 else 0


def step_heading(here: Cell, cell: Cell, cols: int) -> float:
    """The wall's heading of the step from ``here`` to ``cell`` (columns
    wrapping round the seam the short way)."""
    dc = (cell[1] - here[1] + cols // 2) % cols - cols // 2
    return math.atan2(cell[0] - here[0], dc)


def lane_change_turns(prev: Cell | None, cell: Cell, nxt: Cell | None,
                      cols: int) -> tuple[float | None, float | None]:
    """The turns in place round the step ``prev`` → ``cell``: when it is a lane
    change (a sideways step along a row), the heading to face before it (0 or
    π) and, when the route then runs up or down the new lane (``nxt`` in
    ``cell``'s column), the heading to face once there (±π/2); None where no
    turn is made."""
    side = sideways(prev, cell, cols)
    if not side:
        return None, None
    after = (math.copysign(math.pi / 2, nxt[0] - cell[0])
             if nxt is not None and nxt[1] == cell[1] else None)
    return (0.0 if side > 0 else math.pi), after
