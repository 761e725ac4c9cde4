"""The relay executor's record (:class:`.executor.InspectionExecutor`): each probe
sample at the believed pose, a cell visited when the probe enters its core, the
visit's reading nearest the centre filed once per cell and queued for the desk,
and the coverage the desk is told of. Only the estimate and the map are read.
"""

from __future__ import annotations

import numpy as np

from app.comm.wall_protocol import CoverageProgress, CoverageState

CORE = 0.35  # a cell is visited when the probe comes this many D of its centre


class Record:
    """Readings filed per cell and the progress, for the executor (its ``covered``,
    ``filed``, ``pending``, ``lanes``, the visit at hand and the map)."""

    def reading(self, pose: tuple[float, float, float], thickness_mm: float | None) -> None:
        """One probe sample at the believed pose. A cell is visited when the probe
        enters its core (within ``CORE`` · D of its centre, so skimming a corner is
        no visit); of each visit the reading nearest the centre is filed when the
        probe leaves, once per cell (a reading believed over an obstacle is dropped:
        the map says no probe can couple there)."""
        px, py = self.probe_point(pose)
        # every sample is kept until the next x fix, which files them again on the
        # corrected track (:meth:`.sure_lanes.SureLanes.fixed`)
        self.lanes.sample(pose[:2], px, py, thickness_mm)
        cell = self.cell_of(px, py)
        if cell is None or self.map_blocked[cell]:
            self._flush()
            return
        cx, cy = ((k + 0.5) * self.cell_m for k in cell[::-1])
        d = max(abs((px - cx + self.circ_m / 2) % self.circ_m - self.circ_m / 2), abs(py - cy))
        if d <= CORE * self.cell_m:
            if cell != self._cell:
                self._flush()
                self._cell = cell
                self._first = self.lanes.count - (thickness_mm is not None)
                if self.state == CoverageState.RUNNING:
                    self.visits += 1
                    self.turn_visits += bool(self.moves)
            if thickness_mm is not None and (self._best is None or d < self._best[0]):
                self._best = (d, px, py, thickness_mm)
        elif cell != self._cell:
            self._flush()

    def _flush(self) -> None:
        """File the visit's best reading (if its cell has none yet)."""
        cell, best = self._cell, self._best
        self._cell, self._best = None, None
        if cell is None or best is None or self.covered[cell]:
            return
        self.covered[cell] = True
        self.filed[cell] = best[3]
        self.lanes.filed(cell, best[1], self._first)
        self.pending.append(best[1:])

    def refile(self, dx_m: float, sigma_m: float) -> list[tuple[int, int]]:
        """An x fix moved the probe's believed x by ``dx_m`` (its σ ``sigma_m`` after): the
        visit at hand is filed, and the samples since the last fix are filed again on the
        corrected track (:meth:`.sure_lanes.SureLanes.fixed`): a cell filed since then is
        kept with the corrected sample nearest its centre, a cell with no reading that a
        sample was carried into by the correction, surely, is filed (its reading sent at
        the corrected place), and the cells filed since then that no corrected sample is
        surely in are no longer covered (for the mop-up). Returns those."""
        cell = self._cell
        self._flush()
        self._cell, self._first = cell, 0  # (the visit goes on: no second visit counted)
        since = {c for c, _ in self.lanes.since}
        out = self.lanes.fixed(dx_m, sigma_m)
        for c in out:
            self.covered[c] = False
        for c in since & self.lanes.refiled.keys():  # kept: the corrected sample's reading
            self.filed[c] = self.lanes.refiled[c][2]
        for c, (x, y, mm) in self.lanes.moved_in.items():
            if c[0] < self.rows and not self.map_blocked[c] and not self.covered[c]:
                self.covered[c] = True
                self.filed[c] = mm
                self.pending.append((x, y, mm))
                self.anew += 1
        return out

    def take_readings(self) -> np.ndarray:
        rows = np.asarray(self.pending, np.float32).reshape(-1, 3)
        self.pending = []
        return rows

    def progress(self) -> CoverageProgress:
        # (a reading over a cell off the route, out of the body's reach, is filed and
        # sent, but the coverage counts the route's cells)
        return CoverageProgress.build(self.covered & self.reachable_mask, self.reachable,
                                      max(self.visits, int(self.covered.sum())),
                                      self.index, len(self.cells), self.state)
