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

The cells are not simply taken back, though: the robot keeps each probe sample
since the last fix with the believed probe position and how far the belief's axle
had moved since that fix (``s``, of ``S`` in all). The correction is spread back
along the track in proportion to the distance driven (the error grows from naught
at the last fix to −dx at this one; ``f = s/S``): the sample's corrected x is
``x + f·dx``, with the deviation of that interpolation as a Brownian bridge between
the two fixes whose one step is the correction itself, σ² = ((1−f)·σ₀)² + (f·σ₁)²
+ f(1−f)·dx² (σ₀, σ₁ the probe's σ_x after the last fix and after this one). The
samples are filed again at their corrected cells: a cell is kept (its reading the
corrected sample nearest its centre) when a sample lies in its core (:data:`CORE`
of D from its centre) with |x' − centre| + k·σ < D/2, filed anew where no reading
was when the correction carried such a sample there out of the cell the belief had
put it in, and taken back only when no corrected sample is surely in it
(:meth:`SureLanes.fixed`, :attr:`SureLanes.refiled`, :attr:`SureLanes.moved_in`). At
f = 1 the bound is the one above; the cells filed soon after the last fix carry
little of the correction and are kept. Cells filed without their samples (none
kept) are judged by the bound above.

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

Before the estimate's first x fix the lanes can lean more than any of this shows:
the accelerometer's bias is learnt in the first turns in place, sometimes wrong,
and the first lanes then run 10-40 mrad off the vertical with the filter sure of
its heading to 2 mrad (docs/climber.md, "A lean the first fix does not show"). A
heading off by δ moves the x error by δ times the believed height climbed (a
rotation by δ maps (Δx, Δy) to (Δx − δ·Δy, …)), whatever the path: an up lane
and a down lane take it out and back again, and a fix made at the height the
start was made at sees none of it, while the lane between ran δ·H off (on a
4.8 m wall at 15 mrad, 7 cm: traced through the link, a lane of 17 cells filed
and never probed, kept by a first fix of 2.4 cm). The correction spread along
the distance driven cannot tell that, so with ``whole_first`` (an option of the
relay's executor, off: it sends the first lanes to the mop-up on every run) the
first x fix takes back every cell filed before it, for the mop-up, which drives to
them on the estimate the fixes have since put right.

Only the estimate, its covariance and the map are read; the simulator's truth
never is.
"""

from __future__ import annotations

import logging
import math

import numpy as np

__all__ = ["BURST_CELLS", "CORE", "K_SIGMA", "MAX_SAMPLES", "SureLanes", "probe_sigma_x"]

K_SIGMA = 1.0  # a cell is sure when |offset + dx| lies within D/2 − K_SIGMA·σ_x
BURST_CELLS = 0.1  # a run of refusals mended by the reset may have moved x this share of a cell
CORE = 0.35  # a sample files a cell when within this many D of its centre (the record's)
MAX_SAMPLES = 200_000  # samples kept between two fixes (beyond, the oldest half is dropped:
# the cells only they made sure are taken back)

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

    def __init__(self, cell_m: float, circ_m: float, k: float = K_SIGMA,
                 core: float = CORE, whole_first: bool = False) -> None:
        self.cell_m, self.circ_m, self.k, self.core = cell_m, circ_m, k, core
        # the first x fix takes back every cell filed before it (the module's docstring)
        self.whole_first = whole_first
        self.judged = 0  # x fixes made (not reset with the record: the estimate's own)
        self.cols = max(1, round(circ_m / cell_m))
        self.since: list[tuple[Cell, float]] = []  # (cell, believed x offset) since the last fix
        self._from: list[int] = []  # for each of ``since``, the first sample of its visit
        # the probe samples since the last fix: believed probe x, y, the reading, and the
        # belief's axle's distance since the fix (:meth:`sample`)
        self._px: list[float] = []
        self._py: list[float] = []
        self._mm: list[float] = []
        self._s: list[float] = []
        self._dist = 0.0
        self._axle: tuple[float, float] | None = None
        self._dropped = 0  # samples dropped (MAX_SAMPLES) since the last fix
        self.sigma0 = 0.0  # the probe's σ_x after the last fix
        # after :meth:`fixed`: {cell: (corrected x, y, mm)} of the samples surely in a cell,
        # and of those the correction carried there out of the cell the belief had them in
        self.refiled: dict[Cell, tuple[float, float, float]] = {}
        self.moved_in: dict[Cell, tuple[float, float, float]] = {}
        self.kept = 0  # cells filed since a fix kept by their corrected samples (each fix)
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
        self.since, self._from, self._lane, self._leant = [], [], 0, -1
        self._px, self._py, self._mm, self._s = [], [], [], []
        self._dist, self._axle, self._dropped = 0.0, None, 0
        if self._run is not None:  # a run of refusals goes on: judged again from here
            self._run[0], self._run[3] = 0, False

    @property
    def samples(self) -> int:
        """The samples kept since the last fix."""
        return len(self._s)

    @property
    def count(self) -> int:
        """The samples with a reading since the last fix, those dropped included."""
        return len(self._s) + self._dropped

    def sample(self, axle: tuple[float, float], px: float, py: float,
               mm: float | None) -> None:
        """A probe sample with the belief's axle at ``axle`` and the probe at (px, py);
        its reading ``mm`` (None: no echo, only the distance counts)."""
        if self._axle is not None:
            dx = (axle[0] - self._axle[0] + self.circ_m / 2) % self.circ_m - self.circ_m / 2
            self._dist += math.hypot(dx, axle[1] - self._axle[1])
        self._axle = axle
        if mm is None:
            return
        if len(self._s) >= MAX_SAMPLES:
            half = len(self._s) // 2
            for a in (self._px, self._py, self._mm, self._s):
                del a[:half]
            self._dropped += half
        self._px.append(px)
        self._py.append(py)
        self._mm.append(mm)
        self._s.append(self._dist)

    def filed(self, cell: Cell, x_m: float, first: int | None = None) -> None:
        """A reading was filed under ``cell``, taken with the probe believed at ``x_m``
        (``first``: the visit's first sample, :attr:`samples` then; the lane's start)."""
        off = (x_m - (cell[1] + 0.5) * self.cell_m + self.circ_m / 2) % self.circ_m
        if self.since and self.since[-1][0][1] != cell[1]:
            self._lane = len(self.since)  # another column: another lane
        self.since.append((cell, off - self.circ_m / 2))
        self._from.append(self.count if first is None else first)

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
        leant = len(self.since) if self._leant < 0 else self._leant
        first = self.whole_first and self.judged == 0
        self.judged += 1
        if first:  # (a lean before it is not seen in its correction: nothing kept)
            self.refiled, self.moved_in = {}, {}
            out = [cell for cell, _ in self.since]
        elif self._s:
            # the samples before the lane a refusal made unsure, corrected along the track
            upto = (self._from[leant] if leant < len(self.since) else self.count) - self._dropped
            self.refiled, self.moved_in = self._refile(dx_m, sigma_m, max(0, upto))
            out = [cell for cell, _ in self.since if cell not in self.refiled]
            self.kept += len({cell for cell, _ in self.since}) - len(set(out))
        else:  # (no samples kept: the bound on the filed offset alone)
            self.refiled, self.moved_in = {}, {}
            half = self.cell_m / 2 - self.k * sigma_m
            out = [cell for i, (cell, off) in enumerate(self.since)
                   if i >= leant or abs(off + dx_m) >= half]
        self.sigma0 = sigma_m
        self.reset()
        if out:
            self.fixes += 1
            self.unsure += len(out)
            log.info("an x fix moved the belief %.3f m: %d cells filed since the last one are "
                     "not surely in their column", dx_m, len(out))
        return out

    def _refile(self, dx_m: float, sigma_m: float, upto: int) -> tuple[dict, dict]:
        """The samples before ``upto`` at their corrected places: for each cell one of
        them surely lies in (its core, and x within D/2 − k·σ of its centre), the one
        nearest its centre, ``{cell: (x, y, mm)}`` (rows below 0 left out); and the same
        of the samples the correction carried out of the cell the belief had them in
        (a sample that stays in its cell leaves the record's judgement of its visit as
        it was: a correction of a millimetre is no reason to count a skim as a visit)."""
        if upto <= 0:
            return {}, {}
        d = self.cell_m
        s = np.asarray(self._s[:upto])
        f = s / self._dist if self._dist > 0 else np.ones_like(s)
        px = np.asarray(self._px[:upto])
        x = (px + f * dx_m) % self.circ_m
        y = np.asarray(self._py[:upto])
        sig = np.sqrt(((1 - f) * self.sigma0) ** 2 + (f * sigma_m) ** 2
                      + f * (1 - f) * dx_m ** 2)
        col = np.floor(x / d).astype(int) % self.cols
        row = np.floor(y / d).astype(int)
        ex = np.abs(x - (col + 0.5) * d)
        ex = np.minimum(ex, self.circ_m - ex)
        cheb = np.maximum(ex, np.abs(y - (row + 0.5) * d))
        ok = (row >= 0) & (cheb <= self.core * d) & (ex + self.k * sig < d / 2)
        moved = ok & (col != np.floor(px / d).astype(int) % self.cols)
        mm = self._mm

        def best(mask: np.ndarray) -> dict:
            idx = np.nonzero(mask)[0]
            idx = idx[np.argsort(cheb[idx], kind="stable")]  # nearest its centre first
            _, first = np.unique(row[idx] * self.cols + col[idx], return_index=True)
            return {(int(row[i]), int(col[i])): (float(x[i]), float(y[i]), mm[i])
                    for i in idx[first].tolist()}

        return best(ok), best(moved)
