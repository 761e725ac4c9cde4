"""The relay executor's moves between two probe targets, one control period at
a time: turns in place (:mod:`.turns`), and, where the body must be kept on
the wall (:mod:`.reach`), backing off along the heading before a turn whose
sweep would touch an edge or an obstacle, and a straight step along the row
for a lane change at the shell's top or bottom.

A lane change at an edge: the lane ends with the probe over the edge row,
facing the edge. Turning to face along the row and steering the probe onto
the next column's edge cell (the lane change elsewhere) would swing the body's
side past the edge; so the crawler backs off until it can turn, turns to face
along the row, drives one cell straight, and turns to face the edge again,
the probe then over the next column's edge cell (:func:`body_moves`). Only the
estimate and the wall's map are read.
"""

from __future__ import annotations

import math

from .reach import Reach, wrap
from .turns import TURN_TIMEOUT_S, sideways, turn_rate

BACK_MPS = 0.05  # backing off before a turn
MAX_BACK_M = 0.25  # the longest back-off
CLEAR_M = 0.02  # a back-off goes on until the sweep clears by this (for the moves after it)
STEP_MPS = 0.08  # a straight step's top speed
HOLD_GAIN = 2.0  # a straight step holds its heading: ω = gain · error
FACE_TOL_RAD = math.pi / 4  # a target whose probing heading is further off is turned to first

RECOIL_M = 0.05  # after a contact the body backs away this far, against its last motion
ESCAPE_TURNS_RAD = (0.1, -0.1, 0.2, -0.2, 0.3, -0.3)  # out of a wedge, tried (Moves.recoil)
# ... each checked along its sweep every this much: the corners (0.19 m out) move 1 mm
ESCAPE_STEP_RAD = 0.005
# ("turn", heading) | ("clear", heading) | ("step" or "recoil", metres, signed)
Move = tuple[str, float]
Cell = tuple[int, int]


def body_moves(reach: Reach, cells: list[Cell], k: int, pose: tuple[float, float, float],
               cell_m: float, rows: int, cols: int) -> list[Move] | None:
    """The moves before steering the probe onto route cell ``k`` from cell
    ``k − 1``, the body at ``pose`` (the estimate): at a lane change a turn to
    face along the row, or at an edge the back-off, turn, step and turn of the
    module's docstring; up or down a lane, a turn when the cell is probed
    facing the other way (the lane's first cells at an edge are probed facing
    it, reversing away from it). None when the body fits round the cell no way
    (it is given up)."""
    prev, cell = cells[k - 1], cells[k]
    nxt = cells[k + 1] if k + 1 < len(cells) else None
    px, py = (cell[1] + 0.5) * cell_m, (cell[0] + 0.5) * cell_m
    heading = pose[2]
    side = sideways(prev, cell, cols)
    if side:
        along = 0.0 if side > 0 else math.pi
        if reach.fits(px, py, along):
            if abs(math.sin(heading)) > 0.7:
                # facing up or down, with the probe over the cell before: a turn in place
                # would swing the probe a body's half-length down (or up) off the row, and
                # steering it back would turn the body about its centre, its corners
                # swinging round (into a nozzle beside the row); so the body first drives
                # that far on, over the probe, when it fits there and the turn's sweep
                # comes no nearer to what it may touch than from where it is
                c, s_ = math.cos(heading), math.sin(heading)
                cx, cy = pose[0] + reach.lead * c, pose[1] + reach.lead * s_
                here = max(0.0, reach.sweep_depth(pose[0], pose[1], heading, along))
                if (reach.contact.depth(cx, cy, heading, reach.margin)[0] <= 1e-9
                        and reach.sweep_depth(cx, cy, heading, along) <= here + 1e-9):
                    return [("step", reach.lead), ("turn", along)]
            return [("turn", along)]
        if nxt is not None and nxt[0] != cell[0]:
            way = math.copysign(math.pi / 2, nxt[0] - cell[0])
        else:  # (the route runs on along the row) face the nearer edge
            way = -math.pi / 2 if cell[0] < rows / 2 else math.pi / 2
        h = reach.probe_heading(px, py, way)
        return None if h is None else [("turn", along), ("step", cell_m), ("turn", h)]
    way = math.copysign(math.pi / 2, cell[0] - prev[0]) if cell[0] != prev[0] else heading
    h = reach.probe_heading(px, py, way)
    if h is None:
        return None
    if abs(wrap(h - heading)) <= FACE_TOL_RAD:
        return []
    if abs(math.cos(heading)) > 0.7:
        # facing along the row, with the probe over the cell before: a turn up or down
        # in place would swing the probe a body's half-length sideways, and steering it
        # back would turn the body again; so the body first drives that far along the
        # row, under (or over) the probe, when it fits there
        c, s_ = math.cos(heading), math.sin(heading)
        cx, cy = pose[0] + reach.lead * c, pose[1] + reach.lead * s_
        if reach.contact.depth(cx, cy, heading, reach.margin)[0] <= 0:
            return [("step", reach.lead), ("turn", h)]
    back = wrap(h + math.pi)
    if abs(wrap(back - heading)) <= FACE_TOL_RAD and reach.fits(px, py, back) \
            and reach.sweep_depth(pose[0], pose[1], heading, h) > 0:
        # to turn round here would swing the body's corners into what is beside it (a
        # lane's first cells between the shell's edge and a nozzle): it goes on
        # reversing, the probe facing the way it came, and turns round further on
        return []
    return [("turn", h)]


def lift_detour(reach: Reach, route: list[Cell], blocked, cell_m: float) -> list[Cell]:
    """A detour's route (along a lane's end row to a vertical seam and back to
    its last cell, the lane's end) made drivable facing along the row, or []
    when it cannot be (the detour is then left for a later lane change).

    From a lane's end on the shell's top or bottom row, where the body does
    not fit facing along the row, the route is moved to the nearest row where
    it fits both ways (the camera sees the seam there as well), and its legs
    to and from that row go straight along the lane's column: a leg across a
    row and a column at once would have the probe steered sideways next to the
    edge, which swings the body's corners past it. From a lane's end inside
    the wall the route keeps its row. Either way every cell of it must let the
    body face along the row: beside an obstacle it may not (its side over a
    nozzle), and such a detour is not driven."""
    rows = blocked.shape[0]
    if not route:
        return route
    end = route[-1]  # the lane's end, where the detour also starts

    def along(cell: Cell) -> bool:
        x, y = (cell[1] + 0.5) * cell_m, (cell[0] + 0.5) * cell_m
        return reach.fits(x, y, 0.0) and reach.fits(x, y, math.pi)

    if 0 < end[0] < rows - 1:
        return route if all(along(cell) for cell in route[:-1]) else []
    out: list[Cell] = []
    for r, c in route[:-1]:
        toward = 1 if r < rows / 2 else -1
        for rr in range(r, r + toward * (rows // 2), toward):
            if blocked[rr, c]:
                rr = r
                break
            if along((rr, c)):
                break
        else:
            rr = r
        if not out or out[-1] != (rr, c):
            out.append((rr, c))
    if not out or not all(along(cell) for cell in out):
        return []
    lifted = out[0][0]
    if lifted == end[0] or any(cell[0] != lifted for cell in out):
        return []  # (not one row: no straight way back)
    step = 1 if lifted > end[0] else -1
    column = [(r, end[1]) for r in range(end[0] + step, lifted + step, step)]
    if any(blocked[cell] for cell in column):
        return []
    path = column + out + column[::-1] + [end]
    return [cell for k, cell in enumerate(path) if k == 0 or cell != path[k - 1]]


class Moves:
    """The queue of moves the executor makes before its next target; ``step``
    gives one control period's (v, ω), or None once the queue is done."""

    def __init__(self, reach: Reach | None, circ_m: float) -> None:
        self.reach = reach
        self.circ_m = circ_m
        self.queue: list[Move] = []
        self._start: tuple[float, float, float, float, float] | None = None  # t, x, y, θ, way
        self.turns = self.backoffs = self.steps = self.recoils = 0  # moves made, by kind

    def __bool__(self) -> bool:
        return bool(self.queue)

    def set(self, moves) -> None:
        self.queue = list(moves)
        self._start = None

    def recoil(self, last_v: float, turning: bool,
               pose: tuple[float, float, float] | None = None) -> None:
        """The board reported a contact: the moves are given up, and the body backs
        away from what it touched: against its last motion, or, pressed against it
        in a turn in place, back along its heading (``turning``). Given the estimate
        ``pose``, where that recoil goes deeper on the map than the body is now (a
        wedge between two obstacles or an obstacle and the shell's edge, where the
        recoils alternated 5 cm back and 5 cm on for good), the other way, or a small
        turn in place, whichever ends shallowest without going deeper on the way."""
        if abs(last_v) > 1e-3:
            d = -math.copysign(RECOIL_M, last_v)
        elif turning:
            d = -RECOIL_M
        else:
            self.set([])
            return
        free = None if pose is None or self.reach is None else self._free(pose, d)
        self.set(free or [("recoil", d)])

    def _free(self, pose: tuple[float, float, float], d: float) -> list[Move] | None:
        """The move out of a wedge (:meth:`recoil`); None when the recoil ``d`` does not
        go deeper, or nothing else does better (the footprint on the map, no margin). A
        footprint clear on the map is at depth 0: a clear footprint's depth is no distance
        (the shell's far edge, metres off, or a separating axis's gap), and backing away
        from a contact the estimate does not touch (x a few cm off beside the stair band)
        went "deeper" towards the top edge 3 m away, so the recoil went on into the band."""
        x, y, th = pose
        depth = self.reach.contact.depth
        now = max(0.0, depth(x, y, th)[0]) + 1e-4

        def straight(dist: float) -> tuple[float, float]:
            at = self.reach.straight_depths(x, y, th, dist, margin=0.0)
            return max(at), at[-1]

        if straight(d)[0] <= now:
            return None
        options = []
        worst, end = straight(-d)
        if worst <= now:
            options.append((end, [("recoil", -d)]))
        for a in ESCAPE_TURNS_RAD:  # ("turn!": no back-off before it)
            # sampled finely: a corner passing a cell's corner clips it by a few mm between
            # samples 0.05 rad apart (1 cm of the corner's travel); the body stops there, and
            # the same turn was chosen again at every contact report (the stair wall through
            # the link: 2 800 s of turns of 0.1 rad that never began)
            n = max(1, math.ceil(abs(a) / ESCAPE_STEP_RAD))
            at = [depth(x, y, th + a * k / n)[0] for k in range(1, n + 1)]
            if max(at) <= now:
                options.append((at[-1], [("turn!", wrap(th + a))]))
        # the shallowest end; every clear end alike (a clear footprint's depth is no
        # distance: a turn whose end lay 2 mm further from the shell's bottom edge, 0.65 m
        # away, was taken before the straight recoil), the straight recoil first: a turn
        # in place beside a cell's corner is the move a few mm of the estimate's error
        # decides (the stair wall through the link: the body's corner 6 mm on the other
        # side of the band's cell corner from where the estimate put it, and the turn
        # never began)
        return min(options, key=lambda o: max(0.0, o[0]))[1] if options else None

    def step(self, pose: tuple[float, float, float], t: float) -> tuple[float, float] | None:
        while self.queue:
            kind, arg = self.queue[0]
            x, y, th = pose
            if self._start is None:
                way = 0.0
                if kind == "turn" and self.reach is not None \
                        and self.reach.sweep_depth(x, y, th, arg) > 0:
                    # the turn's sweep would touch: back off along the heading first
                    self.queue[0:1] = [("clear", arg), ("turn!", arg)]
                    continue
                if kind == "clear":
                    way = self.reach.back_off_way(x, y, th, arg, MAX_BACK_M)
                    if not way:  # (along an edge: backing off would not help)
                        self.queue.pop(0)
                        continue
                if kind == "step" and self.reach is not None:
                    # planned from where a back-off or a recoil may not have left the
                    # body: only as far as the footprint keeps the margin (a step along
                    # the row under the stair band, whose lower side falls that way)
                    arg = self.reach.straight_reach(x, y, th, arg)
                    if abs(arg) < 0.005:
                        self.queue.pop(0)
                        continue
                    self.queue[0] = (kind, arg)
                self._start = (t, x, y, th, way)
            u = self._run(kind, arg, pose, t)
            if u is not None:
                return u
            self.queue.pop(0)
            self._start = None
            if kind.startswith("turn"):
                self.turns += 1
            elif kind == "clear":
                self.backoffs += 1
            elif kind == "step":
                self.steps += 1
            else:
                self.recoils += 1
        return None

    def _run(self, kind: str, arg: float, pose: tuple[float, float, float],
             t: float) -> tuple[float, float] | None:
        t0, x0, y0, th0, way = self._start
        x, y, th = pose
        if t - t0 >= TURN_TIMEOUT_S:
            return None
        travelled = math.hypot((x - x0 + self.circ_m / 2) % self.circ_m - self.circ_m / 2, y - y0)
        if kind.startswith("turn"):
            w = turn_rate(th, arg)
            return None if w is None else (0.0, w)
        if kind == "clear":
            sweep = self.reach.sweep_depth(x, y, th, arg)
            if travelled >= MAX_BACK_M or sweep <= -CLEAR_M:
                return None
            # going on while it does not make matters worse (along a step of the map's
            # cells the sweep stays as deep for a few cm), and not into something else
            d = 0.01 * way
            if self.reach.sweep_depth(x + d * math.cos(th), y + d * math.sin(th), th,
                                      arg) > sweep + 1e-4 \
                    or abs(self.reach.straight_reach(x, y, th, d)) < abs(d):
                return None
            return way * BACK_MPS, 0.0
        left = abs(arg) - travelled
        if left <= 0.002:
            return None
        return math.copysign(min(STEP_MPS, 1.5 * left + 0.01), arg), HOLD_GAIN * wrap(th0 - th)
