"""Lanes surely in their columns, judged when a landmark fixes the belief's x.

A vertical lane is steered along its column's centre on the estimate; the cells
it files are in the right column only while the belief's x is within half a
cell of the truth. Between two x landmarks (a vertical seam, a manhole's or
nozzle's rim) nothing tells the robot how far it has drifted, and its filter's
σ_x is no guide either way: on the link bench it is 3-6 cm where the true error
is 1 cm, and in a run whose accelerometer bias was learnt wrong in the first
turns it was 2-4 cm where the true error grew to 28 cm (docs/climber.md, "Lanes
lost sideways through the link"). What the robot does learn is the correction
the next x fix makes: the belief was that far off just before it.

So each cell filed is remembered with the believed probe's x offset from the
cell's centre, until the next x fix. When a fix moves the probe's believed x by
``dx``, a cell filed since the last fix was surely in its column if the true
probe was within D/2 of the centre whatever share of that error it carried
then: with the error growing from naught to −dx, the true offset lies between
``offset`` and ``offset + dx``, so the cell is sure when |offset + dx| + k·σ_x
< D/2 (σ_x the probe's x deviation after the fix; |offset| < D/2 always, a
visit's core being 0.35 D). A cell not sure is no longer counted covered, and
the executor's mop-up drives to it again at the end of the sweep (its reading
is filed again there).

An error that grew and shrank again between two fixes is not seen that way:
traced on the link bench, a lane drifted 8 cm sideways while the next fix
found the belief 3 cm off. Every such run had one thing in common, seen by
the estimate itself: its filter refused the accelerometer's gravity heading
(an innovation beyond its gate, ``WallEkf.update_gravity_heading``) while the
lanes leant, where the runs that held their columns refused none on those
lanes. The heading the lanes are steered on then disagrees with the one
absolute heading the robot has, and the lanes' x is unknown until the next x
fix: so the cells filed from the start of the lane in which a gravity heading
was refused until that fix are not sure either (:meth:`SureLanes.refused`).

Not every refusal is such a lean. Through the link a turn in place can come out
with the belief's heading 30-60 mrad off (a gyro sample held over reports the relay
did not get): the filter then refuses the gravity heading about twenty times in a
row and takes it with its reset (``WallEkf.gravity_reset_after``) a second or two
later, the body hardly moved, the lanes right. What such a run of refusals can
have done to the lanes' x is bounded by the estimate itself: the belief's axle
moved ``d`` while its heading was off by at most the largest innovation ``e`` of
the run, so x went wrong by at most d·sin e. A run that ends in the filter's reset
(the belief's heading put on the gravity heading) with that bound within
:data:`BURST_CELLS` of a cell is not counted (:attr:`SureLanes.mended`); any other
run is, from the lane it began in, as soon as the bound passes it, when the run
ends without a reset (a jolt or a lean the belief came back from), or when an x fix
comes while it lasts.

Only the estimate, its covariance and the map are read; the simulator's truth
never is.
"""

from __future__ import annotations

import logging
import math

import numpy as np

__all__ = ["BURST_CELLS", "K_SIGMA", "SureLanes", "probe_sigma_x"]

K_SIGMA = 1.0  # a cell is sure when |offset + dx| lies within D/2 − K_SIGMA·σ_x
BURST_CELLS = 0.1  # a run of refusals mended by the reset may have moved x this share of a cell

Cell = tuple[int, int]

log = logging.getLogger(__name__)


def probe_sigma_x(cov: np.ndarray, theta: float, lead_m: float) -> float:
    """The standard deviation of the probe point's x, x + lead·cos θ, from the
    covariance of the pose (x, y, θ first)."""
    j = np.array([1.0, 0.0, -lead_m * math.sin(theta)])
    return math.sqrt(max(float(j @ cov[:3, :3] @ j), 0.0))


class SureLanes:
    """The cells filed since the last x fix and the judgement a fix makes of them.

    ``cell_m``, ``circ_m``: the wall's cell size and circumference; ``k``: the
    standard deviations of the x after the fix kept inside the cell's half-width."""

    def __init__(self, cell_m: float, circ_m: float, k: float = K_SIGMA) -> None:
        self.cell_m, self.circ_m, self.k = cell_m, circ_m, k
        self.since: list[tuple[Cell, float]] = []  # (cell, believed x offset) since the last fix
        self._lane = 0  # the index in ``since`` where the lane being driven began
        self._leant = -1  # from this index in ``since`` on, nothing is sure (-1: none)
        self.refusals = 0  # the lanes' gravity headings refused by the estimate
        self.mended = 0  # runs of refusals ended by the filter's reset, not counted
        self.counted = 0  # runs of refusals that made the lanes unsure
        # a run of refusals: [lane index, moved m, largest |innov|, counted already]
        self._run: list | None = None
        self.fixes = 0  # x fixes that found cells not sure
        self.unsure = 0  # cells found not sure (each time)
        self.largest_m = 0.0  # the largest correction of the believed x seen

    def reset(self) -> None:
        self.since, self._lane, self._leant = [], 0, -1
        if self._run is not None:  # a run of refusals goes on: judged again from here
            self._run[0], self._run[3] = 0, False

    def filed(self, cell: Cell, x_m: float) -> None:
        """A reading was filed under ``cell``, taken with the probe believed at ``x_m``."""
        off = (x_m - (cell[1] + 0.5) * self.cell_m + self.circ_m / 2) % self.circ_m
        if self.since and self.since[-1][0][1] != cell[1]:
            self._lane = len(self.since)  # another column: another lane
        self.since.append((cell, off - self.circ_m / 2))

    def refused(self, innov_rad: float | None = None) -> None:
        """The estimate refused the gravity heading (its innovation ``innov_rad``):
        the cells filed from the start of the lane being driven until the next x fix
        are not sure, unless the run of refusals this one begins or goes on is mended
        by the filter's reset before the belief has moved far (:meth:`moved`,
        :meth:`resolved`). Without ``innov_rad`` the lane is unsure at once."""
        self.refusals += 1
        if innov_rad is None:
            self._lean(self._lane)
            return
        if self._run is None:
            self._run = [self._lane, 0.0, 0.0, False]
        self._run[2] = max(self._run[2], abs(innov_rad))
        self._check_run()

    def moved(self, d_m: float) -> None:
        """The belief's axle moved ``d_m`` since the last report."""
        if self._run is not None:
            self._run[1] += abs(d_m)
            self._check_run()

    def resolved(self, reset: bool) -> None:
        """The run of refusals ended: the filter took a gravity heading, by its reset
        (``reset``: the belief's heading put on the gravity heading) or as agreeing."""
        if self._run is None:
            return
        lane, _, _, counted = self._run
        self._run = None
        if counted:
            return
        if reset:
            self.mended += 1
        else:
            self._lean(lane)

    def _check_run(self) -> None:
        lane, d_m, e, counted = self._run
        if not counted and d_m * math.sin(min(e, math.pi / 2)) > BURST_CELLS * self.cell_m:
            self._run[3] = True
            self._lean(lane)

    def _lean(self, lane: int) -> None:
        self.counted += 1
        self._leant = lane if self._leant < 0 else min(self._leant, lane)

    def fixed(self, dx_m: float, sigma_m: float = 0.0) -> list[Cell]:
        """An x fix moved the probe's believed x by ``dx_m`` (after − before), its
        x deviation ``sigma_m`` after. Returns the cells filed since the last fix
        that were not surely in their column (and those filed since a gravity heading
        was refused, :meth:`refused`), and starts afresh."""
        self.largest_m = max(self.largest_m, abs(dx_m))
        if self._run is not None and not self._run[3]:  # a run not yet ended: counted
            self._run[3] = True
            self._lean(self._run[0])
        half = self.cell_m / 2 - self.k * sigma_m
        leant = len(self.since) if self._leant < 0 else self._leant
        out = [cell for i, (cell, off) in enumerate(self.since)
               if i >= leant or abs(off + dx_m) >= half]
        self.reset()
        if out:
            self.fixes += 1
            self.unsure += len(out)
            log.info("an x fix moved the belief %.3f m: %d cells filed since the last one are "
                     "not surely in their column", dx_m, len(out))
        return out
