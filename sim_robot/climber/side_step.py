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
by it, and turns back: only when the whole manoeuvre keeps the footprint, grown
by the reach's margin, clear on the map (after a straight move along the
heading first, where the first turn's sweep needs it). Only the map and the
estimate are read.
"""

from __future__ import annotations

import math

from .moves import Move
from .reach import Reach, wrap

OVER_M = (0.0, 0.01, 0.02)  # beyond the lateral error, tried in turn (within a cell's core)
FIRST_M = (0.0, 0.02, -0.02, 0.05, -0.05, 0.1, -0.1, 0.15, -0.15)  # moves along, tried in turn


def side_step(reach: Reach, pose: tuple[float, float, float], lateral: float) -> list[Move] | None:
    """The moves that bring the body, and with it the probe, ``lateral`` metres to the
    left of its heading (negative: to the right), or a little further (OVER_M: a row
    where the body just fits along it is not missed by a mm): a straight move along the
    heading where the turn needs room (FIRST_M, the shortest that gives it), a turn to
    face the side (or away from it), a straight step, a turn back. None when no such
    manoeuvre keeps the footprint clear on the map all the way."""
    x, y, th = pose
    c, s = math.cos(th), math.sin(th)
    nx, ny = -s, c
    for first in FIRST_M:
        if first and abs(reach.straight_reach(x, y, th, first) - first) > 1e-9:
            continue
        x0, y0 = x + first * c, y + first * s
        for over in OVER_M:
            step = math.copysign(abs(lateral) + over, lateral)
            ex, ey = x0 + step * nx, y0 + step * ny
            if reach.contact.depth(ex, ey, th, reach.margin)[0] > 0:
                continue
            for way in (1.0, -1.0):  # face the side and drive on, or face away and reverse
                side = wrap(th + way * math.copysign(math.pi / 2, lateral))
                if reach.sweep_depth(x0, y0, th, side) > 0 \
                        or reach.sweep_depth(ex, ey, side, th) > 0 \
                        or not _clear(reach, x0, y0, side, way * abs(step)):
                    continue
                moves: list[Move] = [("step", first)] if first else []
                return moves + [("turn", side), ("step", way * abs(step)), ("turn", th)]
    return None


def _clear(reach: Reach, x: float, y: float, th: float, dist: float) -> bool:
    """The footprint, grown by the margin, stays clear driving ``dist`` along ``th``."""
    return (reach.contact.depth(x, y, th, reach.margin)[0] <= 0
            and max(reach.straight_depths(x, y, th, dist)) <= 0)
