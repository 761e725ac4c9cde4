"""Seeking the shell's edge before a run along it: a guarded move.

The vertical-lane plan covers the wall's top row (and where obstacles leave
it so, the bottom row) in runs along the shell's edge. On that row the only
height landmark is the edge itself, which the downward camera sees within
8 cm of its image centre. A belief that is more than that off in height when
the run begins never sees the edge, so it is never corrected, and the whole
run is read a row too low (on the 24 m tank: believed 9.58 m, truly
9.16–9.22 m).

So before the plan's next cell in an edge row, when the edge has not been
seen for ``stale_m`` of travel or the belief's height σ is over ``sigma_m``,
the probe moves straight towards that edge at ``speed_mps`` until the camera
sees it (a fix on the edge), and the plan goes on from the corrected belief.
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
    stale_m: float = 0.3  # travel since the edge was last seen that calls for a seek
    sigma_m: float = 0.03  # a height σ above this calls for one too
    speed_mps: float = 0.04  # the probe's speed towards the edge
    max_travel_m: float = 0.6  # the guard: give up after this much travel
    near_m: float = 0.03  # a horizontal fix this close to an edge's line is that edge


class EdgeSeek:
    """When to seek the top or bottom edge, the probe velocity while seeking,
    and when a seek has ended. ``rows``/``cell_m``/``height_m``: the wall's
    grid and the shell's height (y = 0 is the bottom edge)."""

    def __init__(self, rows: int, cell_m: float, height_m: float,
                 config: SeekConfig | None = None) -> None:
        self.rows, self.cell_m, self.height_m = rows, cell_m, height_m
        self.cfg = config or SeekConfig()
        self.side = 0  # TOP or BOTTOM while seeking, else 0
        self._from: tuple[float, float] | None = None  # probe belief where the seek began
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
        edge was seen (the wall's wrap is no concern at a step's length)."""
        if self._last is not None:
            d = math.hypot(px - self._last[0], py - self._last[1])
            if d < 1.0:  # a wrap across the seam is not travel
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

    def before(self, target_row: int, px: float, py: float, sigma_y: float) -> bool:
        """Called as the plan takes ``target_row``'s next cell: whether a seek
        starts (the cell is in an edge row whose edge is stale or the height
        uncertain)."""
        side = TOP if target_row == self.rows - 1 else BOTTOM if target_row == 0 else 0
        if side == 0 or self.active:
            return self.active
        if self._since[side] <= self.cfg.stale_m and sigma_y <= self.cfg.sigma_m:
            return False
        self.side, self._from = side, (px, py)
        self.seeks += 1
        return True

    def velocity(self, px: float, py: float) -> tuple[float, float] | None:
        """The probe's wanted velocity (wall frame) while seeking, or None when
        no seek is on (or this one has just run out of its guard)."""
        if not self.active:
            return None
        assert self._from is not None
        if abs(py - self._from[1]) >= self.cfg.max_travel_m:
            log.info("edge seek gave up after %.2f m: no edge seen", self.cfg.max_travel_m)
            self.given_up += 1
            self._end()
            return None
        return 0.0, self.side * self.cfg.speed_mps

    def abandon(self) -> None:
        """The caller's step budget ran out before the edge or the guard."""
        if self.active:
            self.given_up += 1
            self._end()

    def _end(self) -> None:
        self.side, self._from = 0, None
