"""Seeking the shell's edge when the map says the camera should see it and it
does not: a guarded move.

The wall's top row (and the bottom row) is reached at the ends of the
vertical lanes and, where obstacles leave it so, in runs along the shell's
edge. On that row the only height landmark is the edge itself, which the
downward camera sees within 8 cm of its image centre, and the probe (and
camera) over an edge row's centre is D/2 = 5 cm from it. A belief that is
more than about 8 cm off in height there never sees the edge, so it is
never corrected, and the row is read a row too low or not at all (on the
24 m tank: believed 9.58 m, truly 9.16–9.22 m along the top row).

So when the plan's cell in an edge row has been reached as the belief puts
it, and the camera has not fixed on that edge within the last ``recent_m``
of travel, the belief is off: the probe moves straight towards the edge at
``speed_mps`` until the camera sees it (a fix on the edge), and the plan
goes on from the corrected belief. With a right belief the approach itself
sees the edge and nothing happens: a seek at every lane's end was measured
to turn the lanes' sideways drift faster (docs/climber.md).

The move is guarded by the camera and by its own length: it gives up after
``max_travel_m`` (counted on the belief's own displacement, which is the
encoders' and gyro's: relative travel, right even while the absolute
belief is off). Only the estimate and the wall's map are read; the
simulator's truth never is.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

log = logging.getLogger(__name__)

TOP, BOTTOM = 1, -1


@dataclass(frozen=True)
class SeekConfig:
    recent_m: float = 0.1  # an edge fix within this much travel: the edge is seen
    speed_mps: float = 0.04  # the probe's speed towards the edge
    max_travel_m: float = 0.6  # the guard: give up after this much travel
    near_m: float = 0.03  # a horizontal fix this close to an edge's line is that edge


class EdgeSeek:
    """Whether to seek the top or bottom edge, the probe velocity while
    seeking, and when a seek has ended. ``rows``/``height_m``: the wall's
    grid rows and the shell's height (y = 0 is the bottom edge)."""

    def __init__(self, rows: int, height_m: float, config: SeekConfig | None = None) -> None:
        self.rows, self.height_m = rows, height_m
        self.cfg = config or SeekConfig()
        self.side = 0  # TOP or BOTTOM while seeking, else 0
        self._from_y: float | None = None  # the probe's believed y where the seek began
        self._since = {TOP: math.inf, BOTTOM: math.inf}  # travel since each edge was seen
        self._last: tuple[float, float] | None = None
        self.seeks = self.found = self.given_up = 0

    @property
    def active(self) -> bool:
        return self.side != 0

    def edge_y(self, side: int) -> float:
        return self.height_m if side == TOP else 0.0

    def moved(self, px: float, py: float) -> None:
        """The believed probe point after a control step: travel since each
        edge was seen (a jump of a metre or more is the wall's wrap, not travel)."""
        if self._last is not None:
            d = math.hypot(px - self._last[0], py - self._last[1])
            if d < 1.0:
                for side in self._since:
                    self._since[side] += d
        self._last = (px, py)

    def fixed(self, seen_y: float) -> None:
        """A horizontal line was fixed on, at ``seen_y`` as the corrected belief
        puts it: if that is an edge, that edge has just been seen (and a seek
        for it has found it)."""
        for side in (TOP, BOTTOM):
            if abs(seen_y - self.edge_y(side)) <= self.cfg.near_m:
                self._since[side] = 0.0
                if self.side == side:
                    self.found += 1
                    self._end()

    def arrived(self, row: int, py: float) -> bool:
        """The plan's cell in ``row`` has been reached as the belief puts it
        (probe at believed height ``py``): whether a seek starts (an edge row
        whose edge the camera has not seen within ``recent_m``)."""
        side = TOP if row == self.rows - 1 else BOTTOM if row == 0 else 0
        if side == 0 or self.active:
            return self.active
        if self._since[side] <= self.cfg.recent_m:
            return False
        self.begin(side, py)
        return True

    def begin(self, side: int, py: float) -> None:
        """Start a seek of the ``side`` edge from the believed probe height ``py``
        (:meth:`arrived`, or a caller with a reason of its own: an end the
        estimate is not sure of, :mod:`.sure_ends`)."""
        self.side, self._from_y = side, py
        self.seeks += 1

    def velocity(self, py: float) -> tuple[float, float] | None:
        """The probe's wanted velocity (wall frame) while seeking, or None when
        no seek is on (the edge was found, or the guard has just run out)."""
        if not self.active:
            return None
        assert self._from_y is not None
        if abs(py - self._from_y) >= self.cfg.max_travel_m:
            log.info("edge seek gave up after %.2f m: no edge seen", self.cfg.max_travel_m)
            self.given_up += 1
            self._end()
            return None
        return 0.0, self.side * self.cfg.speed_mps

    def abandon(self) -> None:
        """The caller's step or time budget ran out before the edge or the guard."""
        if self.active:
            self.given_up += 1
            self._end()

    def _end(self) -> None:
        self.side, self._from_y = 0, None
