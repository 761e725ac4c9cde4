"""After a target is given up for contacts: the way round to the next one.

The executor steers the probe straight at its next route cell, which is
beside the last one. After the body has touched something three times on the
way to a target and given it up, its recoils may have left it on the far side
of what it touched: in a tank's run the body pressed against a nozzle on the
nozzle's left while its route ran down the column on the nozzle's right, and
it gave up that whole lane, three contacts a cell, steering straight at each
cell through the nozzle (docs/climber.md). When the next target is not beside
the probe, the route to it along the steps the body fits
(:func:`.seam_detour.grid_path` with :func:`.link_ends.body_steps`) is driven
first. Only the map and the estimate are read.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .seam_detour import grid_path

Cell = tuple[int, int]
MAX_STEPS = 60  # the longest way round looked for (cells)


def way_round(blocked: np.ndarray, here: Cell | None, target: Cell,
              step_ok: Callable[[Cell, Cell], bool] | None) -> list[Cell]:
    """The cells to drive through, from beside the probe's cell ``here`` up to (not
    including) ``target``, along steps the body fits; [] when the target is beside
    ``here`` already, or no such way is found within MAX_STEPS. Where the probe's own
    cell is one the route keeps out of (beside the obstacle), the way starts from the
    free cell nearest it."""
    if here is None:
        return []
    rows, cols = blocked.shape
    if _apart(here, target, cols) <= 1:
        return []
    start = here if not blocked[here] else _nearest_free(blocked, here)
    if start is None:
        return []
    leg = grid_path(blocked, start, {target}, MAX_STEPS, step_ok)
    if not leg or leg[-1] != target:
        return []
    way = ([start] if start != here else []) + leg[:-1]
    return way


def _apart(a: Cell, b: Cell, cols: int) -> int:
    """Chebyshev distance in cells, the columns wrapping round."""
    dc = abs((b[1] - a[1] + cols // 2) % cols - cols // 2)
    return max(abs(b[0] - a[0]), dc)


def _nearest_free(blocked: np.ndarray, cell: Cell, radius: int = 2) -> Cell | None:
    rows, cols = blocked.shape
    best = None
    for dr in range(-radius, radius + 1):
        for dc in range(-radius, radius + 1):
            r, c = cell[0] + dr, (cell[1] + dc) % cols
            if 0 <= r < rows and not blocked[r, c]:
                d = dr * dr + dc * dc
                if best is None or d < best[0]:
                    best = (d, (r, c))
    return None if best is None else best[1]
