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
        # each reading: the true cell and the true probe's point
        self.truth: dict[float, tuple[tuple[int, int], float, float]] = {}
        # the stretches between x fixes: (start s, end s, lane changes, lane ends seen)
        self.gaps: list[tuple[float, float, int, list[tuple[int, int]]]] = []
        self._since = 0.0
        self._ends: list[tuple[int, int]] = []
        # detours: from, cells (both ways), the far end
        self.routes: list[tuple[tuple[int, int], int, tuple[int, int]]] = []
        trace = self

        class Traced(SeamDetour):
            def __init__(self, *args, **kwargs) -> None:
                super().__init__(*args, **kwargs)
                trace.detour = self

            def route(self, here, *args, **kwargs):
                trace._ends.append(tuple(here))
                out = super().route(here, *args, **kwargs)
                if out:
                    trace.routes.append((tuple(here), len(out), out[len(out) // 2 - 1]))
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
                self.truth[reading] = (world.cell_of(x_m, y_m), x_m, y_m)
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
        rows, d = self.world.rows, self.world.cell_m
        out = [f"stretches between x fixes (a lane change or a minute without one): "
               f"{len(self.gaps)}; detours driven {len(self.routes)}, "
               f"{sum(n for _, n, _ in self.routes)} cells; "
               f"{sum(far[0] != here[0] for here, _, far in self.routes)} of them to another "
               f"row, {sum(here[0] in (0, rows - 1) for here, _, _ in self.routes)} from an "
               f"edge row"]

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
        off = []  # (filed cell, true cell, how far the true probe was outside the filed cell)
        for r, c in zip(*np.nonzero(np.isfinite(res.filed)), strict=True):
            got = self.truth.get(float(res.filed[r, c]))
            if got is None or got[0] == (r, c):
                continue
            true, x, y = got
            ox = abs(self.world.wrap_dx(x - (c + 0.5) * d)) - d / 2
            oy = abs(y - (r + 0.5) * d) - d / 2
            off.append(((int(r), int(c)), true, max(ox, oy, 0.0)))
        sideways = [o for o in off if o[1][0] == o[0][0]]

        def beyond(sel, m) -> int:
            return sum(o[2] > m for o in sel)

        out.append(f"cells filed with the true probe in another cell: {len(off)}, "
                   f"{beyond(off, 0.01)} of them more than 1 cm outside it, "
                   f"{beyond(off, 0.025)} more than 2.5 cm; in the same row (x): "
                   f"{len(sideways)}, {beyond(sideways, 0.01)} more than 1 cm, "
                   f"{beyond(sideways, 0.025)} more than 2.5 cm; the farthest "
                   f"{max((o[2] for o in off), default=0.0) * 100:.1f} cm")
        worst = sorted(off, key=lambda o: -o[2])[:5]
        out.append("  the farthest: " + ", ".join(
            f"{o[0]} (true {o[1]}, {o[2] * 100:.1f} cm out)" for o in worst))
        if box is not None:
            r0, r1, c0, c1 = box
            boxed = [o for o in off if r0 <= o[0][0] <= r1 and c0 <= o[0][1] <= c1]
            side = [o for o in boxed if o[1][0] == o[0][0]]
            far = [o[0] for o in side if o[2] > 0.01]
            never = [o[0] for o in boxed if math.isnan(res.measured[o[0]])]
            out.append(f"  of them in rows {r0}-{r1}, columns {c0}-{c1}: {len(boxed)}; in the "
                       f"same row {len(side)}, {len(far)} more than 1 cm outside "
                       f"{far[:12]}{' ...' if len(far) > 12 else ''}; "
                       f"never truly probed: {len(never)} {never[:12]}")
        return out
