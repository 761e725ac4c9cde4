"""Coverage round the tank: plans that may cross the wall's seam.

The unrolled wall wraps round (issue 14, step 1): columns 0 and W−1 are
neighbours. :func:`.plan.best_plan` does not wrap, and no straight column
can be cut out of the ring without losing cells when a full-height obstacle
(the spiral stair's diagonal band) already divides the wall, so
:func:`wrap_plan` plans on the ring itself:

1. the walker's plan with the seam (:func:`.plan.plan_coverage`,
   ``wrap=True``), as the climber planned before;
2. lane tours with the seam (:func:`.lanes.lane_tour`, ``wrap=True``): the
   whole ring in lanes along the given axis (both axes when none is given),
   with the iterated local search on small walls;
3. each candidate polished as best_plan polishes its own (:mod:`.prune`,
   :mod:`.untwist`, :mod:`.relocate`, :func:`.plan.straightened`), which do
   not wrap: on the wall rolled so that its edge falls where the path
   crosses fewest column boundaries. They keep every step they do not
   touch, check every new one without the seam (so none crosses the edge)
   and keep every cell visited; the few turns they misjudge next to the
   path's crossings of the edge are caught by step 4, which counts them
   round the ring, the unpolished candidate staying in the running;
4. the one with the fewest changes of heading among those whose repetition
   is within the cap (Definition 7; turns cost wall, seed 001 eq. 3), else
   the least repeated cells + ``turn_weight`` per turn — as in best_plan.

Coverage, 8-adjacency (across the seam), free cells and no corner cutting
hold for every candidate by construction.
"""

from __future__ import annotations

import logging
import time

import numpy as np

from . import _kernels as K
from .lanes import lane_tour
from .measure import _check
from .plan import (
    LANE_KICKS,
    LANE_LAMBDA,
    MAX_REPETITION,
    RELOCATE_LEN,
    CoveragePlan,
    plan_coverage,
    straightened,
)
from .prune import prune
from .relocate import relocate
from .untwist import two_opt

log = logging.getLogger(__name__)

SMALL = 20_000  # reachable cells up to which the lane orders get the kicks
# How far (steps) the lane ends look for each other: the lanes' default on
# small walls, half of it on big ones (the searches are most of the CPU on
# the full tank; on the default wall the vertical-lane plan is the same)
RADIUS, BIG_RADIUS = 48, 24


def wrap_turns(arr: np.ndarray, w: int) -> int:
    """Changes of heading of a path of flat cells on the ring (a step from
    column W−1 to 0 heads the same way as one from c to c + 1)."""
    if len(arr) < 3:
        return 0
    dr = np.diff(arr // w)
    dc = np.diff(arr % w)
    dc = np.where(dc > 1, dc - w, np.where(dc < -1, dc + w, dc))
    return int(((dr[1:] != dr[:-1]) | (dc[1:] != dc[:-1])).sum())


def quiet_edge(arr: np.ndarray, w: int) -> int:
    """The column k whose boundary with k − 1 (the seam for k = 0) the path
    crosses least often."""
    c = arr % w
    c0, c1 = c[:-1], c[1:]
    moved = c0 != c1
    boundary = np.where(np.abs(c1 - c0) > 1, 0, np.maximum(c0, c1))[moved]
    return int(np.argmin(np.bincount(boundary, minlength=w)))


def polished(a: np.ndarray, arr: np.ndarray, small: bool) -> np.ndarray:
    """The path (flat cells) pruned, untwisted, relocated and straightened on
    the wall rolled to put its edge at :func:`quiet_edge` (see the module)."""
    w = a.shape[1]
    if len(arr) < 3:
        return arr
    cut = quiet_edge(arr, w)
    rolled = np.roll(a, -cut, axis=1)
    free = np.ascontiguousarray(~rolled, dtype=np.uint8)
    x = (arr // w) * w + (arr % w - cut) % w
    passes = 20 if small else 2
    x = prune(free, x, 10)
    two_opt(free, x, passes)
    relocate(free, x, RELOCATE_LEN, passes)
    x = prune(free, x, 10)
    cells = list(zip((x // w).tolist(), (x % w).tolist(), strict=True))
    p = CoveragePlan(cells, rolled, [], np.zeros(0), 0.0)
    p = straightened(rolled, p, window=5 if small else 4)
    x = np.array([r * w + c for r, c in p.cells], dtype=np.int64)
    return (x // w) * w + (x % w + cut) % w


def wrap_plan(
    blocked,
    start,
    regions: bool = False,
    axis: int | None = None,
    max_repetition: float | None = MAX_REPETITION,
    turn_weight: float = 0.02,
) -> CoveragePlan:
    """A coverage plan of every free cell reachable from ``start`` round the
    seam: the walker's (``regions``, ``axis`` as for
    :func:`.plan.plan_coverage`) or a lane tour (lanes along ``axis``, or
    along rows and along columns when it is None), whichever turns least
    within ``max_repetition`` of the reachable cells (see the module).
    ValueError on a start outside the map or on a blocked cell."""
    a, (r0, c0) = _check(blocked, start)
    w = a.shape[1]
    t0 = time.perf_counter()
    free = np.ascontiguousarray(~a, dtype=np.uint8)
    reach = K.flood(free, r0 * w + c0, True)
    n = int(reach.sum())
    walker = plan_coverage(a, (r0, c0), regions=regions, axis=axis, wrap=True)
    cands = [(np.array([r * w + c for r, c in walker.cells], dtype=np.int64), walker)]
    whole = np.where(reach > 0, 0, -1).astype(np.int32)
    rfree = np.ascontiguousarray(reach > 0, dtype=np.uint8)
    kicks, radius = (LANE_KICKS, RADIUS) if n <= SMALL else (0, BIG_RADIUS)
    for ax in (0, 1) if axis is None else (axis,):
        axes = np.array([ax], dtype=np.int64)
        arr = lane_tour(
            rfree, whole, axes, r0 * w + c0, LANE_LAMBDA, radius=radius, kicks=kicks, wrap=True
        )
        cells = list(zip((arr // w).tolist(), (arr % w).tolist(), strict=True))
        cands.append((arr, CoveragePlan(cells, whole, [], axes, 0.0)))
    cands += [(polished(a, arr, n <= SMALL), p) for arr, p in cands]
    cap = None if max_repetition is None else max_repetition * n

    def key(arr: np.ndarray) -> tuple:
        repeats, turns = len(arr) - n, wrap_turns(arr, w)
        if cap is not None and repeats <= cap:
            return (0, turns, repeats)
        return (1, repeats + turn_weight * turns, 0)

    keys = [key(arr) for arr, _ in cands]
    i = min(range(len(cands)), key=lambda j: (keys[j], j))
    arr, p = cands[i]
    ms = (time.perf_counter() - t0) * 1e3
    log.debug("wrap plan: %d cells, candidates %s, took %d, %.1f ms", n, keys, i, ms)
    cells = list(zip((arr // w).tolist(), (arr % w).tolist(), strict=True))
    return CoveragePlan(cells, p.labels, p.order, p.axes, ms)
