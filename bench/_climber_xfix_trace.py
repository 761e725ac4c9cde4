"""The headless inspection's stretches without an x fix and its filings against the
simulator's truth (for bench/climber_inspection_bench.py ``--x-fix-trace``; the robot
never reads it).

``inspect_wall`` tells its detours (:class:`~sim_robot.climber.seam_detour.SeamDetour`)
of each x fix (a vertical seam or a rim seen) and of each lane change; a subclass put in
its place records both, with the simulated time (the camera is asked once a control
step, so its calls count the steps) and the lane end at each lane change. The world's
probe is wrapped to note the true cell of each reading; a filed reading is then traced
back to the cell it was truly read in (the readings carry the probe's noise, so each is
one float of its own)."""

from __future__ import annotations

import inspect as pyinspect
import math

import numpy as np

import sim_robot.climber.inspection as inspection
from sim_robot.climber.seam_detour import SeamDetour


class XFixTrace:
    """Install before ``inspect_wall`` runs on ``world``; :meth:`report` after it."""

    def __init__(self, world) -> None:
        self.world = world
        self.dt_s = pyinspect.signature(inspection.inspect_wall).parameters["dt_s"].default
        self.steps = 0
        self.truth: dict[float, tuple[int, int]] = {}
        # the stretches between x fixes: (start s, end s, lane changes, lane ends seen)
        self.gaps: list[tuple[float, float, int, list[tuple[int, int]]]] = []
        self._since = 0.0
        self._ends: list[tuple[int, int]] = []
        self.routes: list[tuple[tuple[int, int], int]] = []  # detours: from, cells
        trace = self

        class Traced(SeamDetour):
            def __init__(self, *args, **kwargs) -> None:
                super().__init__(*args, **kwargs)
                trace.detour = self

            def route(self, here, *args, **kwargs):
                trace._ends.append(tuple(here))
                out = super().route(here, *args, **kwargs)
                if out:
                    trace.routes.append((tuple(here), len(out)))
                return out

            def fixed(self, dx_m=None) -> None:
                trace._close(self.lanes)
                super().fixed(dx_m)

        self.detour: SeamDetour | None = None
        self.detour_cls = Traced
        inspection.SeamDetour = Traced
        sightings, probe = world.seam_sightings, world.probe

        def seam_sightings(*args, **kwargs):
            self.steps += 1
            return sightings(*args, **kwargs)

        def probe_at(x_m: float, y_m: float):
            reading = probe(x_m, y_m)
            if reading is not None:
                self.truth[reading] = world.cell_of(x_m, y_m)
            return reading

        world.seam_sightings, world.probe = seam_sightings, probe_at

    def now(self) -> float:
        return self.steps * self.dt_s

    def _close(self, lanes: int) -> None:
        t = self.now()
        if lanes > 0 or t - self._since > 60.0:
            self.gaps.append((self._since, t, lanes, self._ends))
        self._since, self._ends = t, []

    def report(self, res, box: tuple[int, int, int, int] | None = None) -> list[str]:
        """Lines to print: the longest stretches without an x fix (by lane changes and by
        simulated seconds), the detours, and the cells filed with the true probe in another
        cell (in ``box`` = (row0, row1, col0, col1), inclusive, and elsewhere)."""
        lanes = self.detour.lanes if self.detour is not None else 0
        self.gaps.append((self._since, res.sim_time_s, lanes, self._ends))  # (the run's end)
        out = [f"stretches between x fixes (a lane change or a minute without one): "
               f"{len(self.gaps)}; detours driven {len(self.routes)}, "
               f"{sum(n for _, n in self.routes)} cells"]

        def where(ends) -> str:
            if not ends:
                return "no lane end"
            cols = [c for _, c in ends]
            rows = [r for r, _ in ends]
            return (f"{len(ends)} lane ends in columns {min(cols)}-{max(cols)}, "
                    f"rows {min(rows)}-{max(rows)}")

        by_lanes = sorted(self.gaps, key=lambda g: -g[2])[:5]
        out.append("longest stretches without an x fix, by lane changes: " + "; ".join(
            f"{g[2]} lanes, {g[1] - g[0]:.0f} s from {g[0]:.0f} s ({where(g[3])})"
            for g in by_lanes))
        by_time = sorted(self.gaps, key=lambda g: g[0] - g[1])[:5]
        out.append("longest stretches without an x fix, by simulated time: " + "; ".join(
            f"{g[1] - g[0]:.0f} s from {g[0]:.0f} s, {g[2]} lanes ({where(g[3])})"
            for g in by_time))
        if box is not None:
            r0, r1, c0, c1 = box
            inside = [g for g in self.gaps
                      if g[3] and all(r0 <= r <= r1 and c0 <= c <= c1 for r, c in g[3])]
            worst = max(inside, key=lambda g: g[1] - g[0], default=None)
            if worst is not None:
                out.append(f"longest stretch without an x fix with every lane end in rows "
                           f"{r0}-{r1}, columns {c0}-{c1}: {worst[1] - worst[0]:.0f} s, "
                           f"{worst[2]} lanes ({where(worst[3])})")
            else:
                out.append(f"no stretch without an x fix with every lane end in rows "
                           f"{r0}-{r1}, columns {c0}-{c1}")
        off = []
        for r, c in zip(*np.nonzero(np.isfinite(res.filed)), strict=True):
            true = self.truth.get(float(res.filed[r, c]))
            if true is not None and true != (r, c):
                off.append(((int(r), int(c)), true))
        cols = self.world.cols

        def apart(a, b) -> int:
            dc = abs(a[1] - b[1])
            return max(abs(a[0] - b[0]), min(dc, cols - dc))

        sideways = [(c, t) for c, t in off if t[0] == c[0]]
        out.append(f"cells filed with the true probe in another cell: {len(off)} "
                   f"({len(sideways)} in the same row; the farthest "
                   f"{max((apart(c, t) for c, t in off), default=0)} cells off)")
        if box is not None:
            r0, r1, c0, c1 = box
            boxed = [(c, t) for c, t in off if r0 <= c[0] <= r1 and c0 <= c[1] <= c1]
            never = [c for c, _ in boxed if math.isnan(res.measured[c])]
            side = [c for c, t in boxed if t[0] == c[0]]
            out.append(f"  of them in rows {r0}-{r1}, columns {c0}-{c1}: {len(boxed)}, "
                       f"{len(side)} in the same row {side[:12]}"
                       f"{' ...' if len(side) > 12 else ''}; "
                       f"never truly probed: {len(never)} {never[:12]}")
        return out
