"""Back to the route from where the body is, when its next cell is not beside the
probe (the relay's executor, :mod:`.executor`).

The executor steers the probe from one route cell to the next, which lie side by side.
When it gives a cell up (its third contact on the way there, or the cell out of the
body's reach), the next may lie far off: the upper cells of a lane while the body is
still at its foot, under a nozzle by the shell's bottom. Steered there straight, the
body drove into what lay between, was stopped, gave that cell up too, and the next,
one after another without moving: on the whole tank through the link
(``bench/climber_link_bench.py --wall tank``) thousands of cells went so. Now, when
the route's next cell is more than one cell from the probe's (columns wrapping round),
the way there is driven first: the fewest straight steps over the cells the body fits
along, as the routes to a height landmark take them (:func:`.link_ends.body_steps`,
:func:`.seam_detour.grid_path`), inserted into the route before the cell. Once per
target: a way given up in its turn is not looked for again. Only the map and the
estimate are read.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .seam_detour import grid_path

Cell = tuple[int, int]
JOIN_STEPS = 400  # the longest way back to the route looked for (cells)


class Rejoin:
    """The ways back to the route inserted so far, the last one's span in it."""

    def __init__(self, blocked: np.ndarray, step_ok: Callable[[Cell, Cell], bool] | None,
                 max_steps: int = JOIN_STEPS) -> None:
        self.blocked = np.asarray(blocked, bool)
        self.step_ok = step_ok
        self.max_steps = max_steps
        self.joins = self.cells = 0  # ways inserted, and their cells
        self.reset()

    def reset(self) -> None:
        """A new run of the route."""
        self.start = self.end = 0
        self._done: set[Cell] = set()

    def on_way(self, k: int) -> bool:
        """Route index ``k`` is a cell of the last way inserted."""
        return self.start <= k < self.end

    def way(self, here: Cell | None, target: Cell) -> list[Cell]:
        """The cells to drive from ``here`` (the probe's cell) before ``target``, in
        order; [] when ``target`` is beside ``here`` (or is it), when no way is found
        within ``max_steps``, or when a way to it was inserted before."""
        if here is None or self.blocked[here] or target in self._done:
            return []
        cols = self.blocked.shape[1]
        dc = (target[1] - here[1] + cols // 2) % cols - cols // 2
        if max(abs(target[0] - here[0]), abs(dc)) <= 1:
            return []
        self._done.add(target)
        return grid_path(self.blocked, here, {target}, self.max_steps, self.step_ok)[:-1]

    def inserted(self, k: int, n: int) -> None:
        """``n`` cells were inserted into the route at index ``k``."""
        self.start, self.end = k, k + n
        self.joins += 1
        self.cells += n
