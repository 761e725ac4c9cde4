"""A sideways step to a target off to the side, where the steering may not turn.

The executor steers the probe at its next route cell by turning the body about
its centre. Beside an obstacle that swings a corner into it, so there the probe
is driven along the heading only and its lateral error is left
(``InspectionExecutor._would_touch``). In a tank's run the route ran along the
row just above a low nozzle, the body beside the nozzle facing along the row
with its probe a row low: driven along its heading, it went into the nozzle's
top, and each target beside it was given up after three contacts (about
14 000 s of sim time there, docs/climber.md); where the way along was clear,
the target was passed level with its centre, unread. So when the lateral error
is larger than a cell's core, the body turns to face the side, steps sideways
by it, and turns back (:class:`.moves.Moves` makes the moves, backing off first
where a turn's sweep would touch). Only the map and the estimate are read.
"""

from __future__ import annotations

import math

from .moves import Move
from .reach import Reach, wrap

OVER_M = (0.0, 0.01, 0.02)  # beyond the lateral error, tried in turn (within a cell's core)


def side_step(reach: Reach, pose: tuple[float, float, float], lateral: float) -> list[Move] | None:
    """The turn, sideways step and turn back that move the body, and with it the probe,
    ``lateral`` metres to the left of its heading (negative: to the right), or a little
    further (OVER_M: a row where the body just fits along it is not missed by a mm);
    None when the body fits there no way, or the way sideways is not clear. Of facing
    the side and driving on, or facing away from it and reversing, the one whose turns
    sweep less deep."""
    x, y, th = pose
    nx, ny = -math.sin(th), math.cos(th)
    for over in OVER_M:
        step = math.copysign(abs(lateral) + over, lateral)
        ex, ey = x + step * nx, y + step * ny
        if reach.contact.depth(ex, ey, th, reach.margin)[0] <= 0:
            break
    else:
        return None
    best: tuple[float, list[Move]] | None = None
    for way in (1.0, -1.0):
        side = wrap(th + way * math.copysign(math.pi / 2, lateral))
        dist = way * abs(step)
        if abs(reach.straight_reach(x, y, side, dist)) < abs(step) - 1e-3:
            continue
        worst = max(reach.sweep_depth(x, y, th, side), reach.sweep_depth(ex, ey, side, th))
        if best is None or worst < best[0]:
            best = (worst, [("turn", side), ("step", dist), ("turn", th)])
    return None if best is None else best[1]
