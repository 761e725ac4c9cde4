"""The complete-coverage plan: seed 001's steps joined (§3–4).

:func:`plan_coverage` makes one plan:

1. cells reachable from the start (the rest cannot be covered);
2. sub-regions by the rectangle decomposition (§3.2), or the whole map as one;
3. their order: the depth-first walk on eq. 5's matrix (§3.3), or, by
   default, the region whose associated cell is nearest the exit (eq. 11);
4. each region swept along the direction with fewer turns (§3.4, eqs. 2–3)
   by the compiled walker (:mod:`._kernels`), with one of three sets of
   move preferences (FAMILIES);
5. a dead zone is left by the shortest way to the nearest uncovered cell of
   the region: where the f_i rule of eqs. 6–9 steers, but the rule is
   greedy and can stall in a pocket, so the plan takes the breadth-first
   shortest path (fewest cells, hence fewest repeats);
6. a finished region hands over through the nearest uncovered associated
   cell (§4, eq. 11).

:func:`best_plan` (behind :func:`coverage_path`) makes several, the paper's
pipeline and lane tours (:mod:`.lanes`, whole lanes and, on small maps,
lanes cut beside their neighbours' ends) among them, drops the visits each
does not need (:mod:`.prune`: fewer repeats, no more turns), brings a lane
tour over the repetition cap within it where it can (:mod:`.repair`: each
repeat traded for the fewest added turns), untwists each
by 2-opt (:mod:`.untwist`: same cells, same visits, fewer turns),
moves stretches of the leaders to where they
continue a lane (or-opt, :mod:`.relocate`, same visits), keeps the one with
the fewest turns within the repetition cap, and reorders short windows of
it to turn less (:func:`straightened`); on small maps the repeats the cap
leaves unused are spent where each saves the most turns (:mod:`.spend`)
and the plan is kicked out of its local optimum and searched again
(:mod:`.kick`, with stretches exchanged, :mod:`.exchange`, and its repeats
moved within the cap).
On the bench maps the whole-map walks mostly win:
the sub-regions add travel between them (see docs/coverage.md).

Figures (Definition 7): :mod:`.measure`.
"""

from __future__ import annotations

import itertools
import logging
import time
from dataclasses import dataclass, replace

import numpy as np

from . import _kernels as K
from ._walker import walk
from .decompose import decompose, region_boxes
from .extra import extra_tours, polished_tour
from .kick import polish
from .lanes import lane_set, lane_tour, prepared_sets
from .measure import _check
from .order import adjacency_matrix, dfs_order
from .prune import prune
from .relocate import relocate
from .repair import repair
from .search import searched
from .spend import spend
from .sweep import sweep_axes
from .switch import corner_table
from .untwist import move_masks, two_opt_masked

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class CoveragePlan:
    cells: list[tuple[int, int]]
    labels: np.ndarray
    order: list[int]
    axes: np.ndarray
    time_ms: float


# Move preferences of the walker (see _kernels.sweep_step): scores for on
# along the lane, next lane across, next lane diagonally, back along the lane,
# the previous lane; an orphan; the weight of a candidate's open neighbours;
# random tie-breaking (0 = none); the penalty for changing heading.
FAMILIES = {
    "lanes": (0, 1, 1, 2, 2, -1, 3, 0, 0),  # boustrophedon first: few turns
    "lanes-edge": (0, 1, 1, 2, 2, -1, 8, 0, 0),  # lanes, leaning towards cells by the edge
    "lanes-hug": (0, 1, 1, 2, 2, -1, 16, 0, 0),  # lanes that mostly follow the edge
    "hug": (0, 0, 0, 0, 0, -1, 16, 0, 20),  # fewest open neighbours first, then straight on
    "hug-straight": (0, 0, 0, 0, 0, -1, 16, 0, 40),  # the same, keeping its heading harder
    "tight": (0, 0, 0, 0, 0, -1, 1, 0, 0),  # fewest open neighbours first
}
BIG_FAMILIES = ("lanes", "hug", "tight")  # the candidates on maps of over 20 000 cells


_LAST_TABLES: list = [None]  # (key, bbox, corners) of the last labels seen


def _tables(labels: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Region boxes and associated cells (eq. 11) of ``labels``; the last
    result is kept, since best_plan walks the same whole-map labels dozens
    of times (read-only arrays: the walker never writes them)."""
    key = (labels.shape, count, labels.tobytes())
    last = _LAST_TABLES[0]
    if last is not None and last[0] == key:
        return last[1], last[2]
    bbox, corners = region_boxes(labels, count), corner_table(labels, count)
    bbox.flags.writeable = corners.flags.writeable = False
    _LAST_TABLES[0] = (key, bbox, corners)
    return bbox, corners


def plan_coverage(
    blocked,
    start,
    regions: bool = True,
    family: str = "lanes",
    seed: int = 0,
    order: str = "nearest",
    wrap: bool = False,
    axis: int | None = None,
    labels: np.ndarray | None = None,
) -> CoveragePlan:
    """One coverage plan of every free cell reachable from ``start``.

    regions: sweep the sub-regions of §3.2 one by one (else the whole map is
    one region); family: the walker's move preferences (FAMILIES); seed > 0
    breaks ties at random; order: "dfs" (§3.3) or "nearest" (eq. 11 over all
    unfinished regions); wrap: columns 0 and W−1 are neighbours (the seam);
    axis: force the lanes along rows (0) or columns (1) in every region;
    labels: use these regions (int, −1 = none) instead of the decomposition."""
    if order not in ("dfs", "nearest"):
        raise ValueError(f"order must be 'dfs' or 'nearest', got {order!r}")
    if family not in FAMILIES:
        raise ValueError(f"family must be one of {sorted(FAMILIES)}, got {family!r}")
    t0 = time.perf_counter()
    a, (r0, c0) = _check(blocked, start)
    w = a.shape[1]
    path, labels, seq, axes = _walked(a, (r0, c0), regions, family, seed, order, wrap, axis, labels)
    cells = list(zip((path // w).tolist(), (path % w).tolist(), strict=True))
    ms = (time.perf_counter() - t0) * 1e3
    log.debug("coverage: %d regions, %d steps, %.1f ms", len(axes), len(cells), ms)
    return CoveragePlan(cells, labels, seq, axes, ms)


def _walked(a, start, regions, family, seed, order, wrap, axis, labels, reach=None, nbr=None):
    """plan_coverage's walk on a checked map: (flat path, labels, region
    order, axes); ``reach`` (the flood from start) and ``nbr`` (its
    neighbour table) when already known."""
    r0, c0 = start
    w = a.shape[1]
    if reach is None:
        free = np.ascontiguousarray(~a, dtype=np.uint8)
        reach = K.flood(free, r0 * w + c0, wrap)
    if nbr is None:
        nbr = K.neighbour_table(reach, wrap)
    if labels is not None:
        labels = np.where(reach > 0, labels, -1).astype(np.int32)
    elif regions:
        labels = decompose(reach == 0).labels
    else:
        labels = np.where(reach > 0, 0, -1).astype(np.int32)
    labels = np.ascontiguousarray(labels, dtype=np.int32)
    count = int(labels.max()) + 1
    axes = sweep_axes(labels, count) if axis is None else np.full(count, axis, dtype=np.int64)
    bbox, corners = _tables(labels, count)
    first = int(labels[r0, c0])
    seq = dfs_order(adjacency_matrix(labels, count), first) if order == "dfs" else [first]
    weights = np.array(FAMILIES[family], dtype=np.int64)
    if seed > 0:
        weights[7] = 16
    path, _visits = walk(
        reach,
        labels,
        np.asarray(seq, dtype=np.int64),
        axes,
        bbox,
        corners,
        r0 * w + c0,
        wrap,
        order == "nearest",
        weights,
        seed,
        nbr,
    )
    return path, labels, seq, axes


def _turns(arr: np.ndarray, w: int) -> int:
    """Changes of heading of a path of flat cells (no wrap)."""
    if len(arr) < 3:
        return 0
    dr, dc = np.diff(arr // w), np.diff(arr % w)
    return int(((dr[1:] != dr[:-1]) | (dc[1:] != dc[:-1])).sum())


# Longest stretch that relocate() carries elsewhere (a short lane).
RELOCATE_LEN = 30
RELOCATE_LEADERS = 8  # candidates that get relocate() in best_plan
BIG_LEADERS = 3  # the same above 20 000 reachable cells (CPU on the full wall)

# Lane tours: cost of each cell crossed between lanes, in turns (.lanes).
LANE_LAMBDA = 1.5
LANE_RADIUS = 48  # how far the lane ends' distances are searched (.lanes.end_distances)
LANE_KICKS = 40  # iterated local search on the whole-map lane orders (small maps)
# Links of 2 to LANE_TURN_RADIUS steps priced by their fewest turns (.links),
# and iterated local search by double bridges of at most LANE_SPAN lanes.
LANE_TURN_RADIUS = 12
LANE_SPAN = 8
# the full wall's lane tour: this many rounds, each followed by a local
# search near its bridge (about 0.15 s CPU)
BIG_KICKS = 1000

# More candidates after the winner (.extra), judged on the final plan:
EXTRA_LAMBDAS = (LANE_LAMBDA,)  # link costs of the extra lane tours
EXACT_LAMBDAS = (1.0,)  # link costs of those priced by their turns (.links)
EXTRA_LEADERS = 4  # extra candidates straightened (half on larger maps: CPU)

# Lane tours over the cap are repaired (.repair), and the winner's unused repeats
# spent (.spend), on maps up to this many reachable cells (paper-like; CPU on crowded).
REPAIR_CELLS = 3000
# On those maps the plan is kicked (.kick; in place of the extra lane tours)
# at most KICKS times from more than one start (.search: each start
# KICK_HEAT kicks, then the live run that turns least, a run stalled after
# KICK_STALL kicks without fewer turns); after each kick KICK_ROUNDS rounds
# of 2-opt and or-opt (stretches ≤ KICK_RELOCATE_LEN; exchanges only at the
# end, EXCHANGES passes), KICK_DROPS repeats dropped and the cap's room
# spent again (0: the visits stay fixed).
KICKS = 600
# A kick's local search (2-opt, or-opt, the spend) scans the whole path, and
# a map cut into many short lanes has many places to try: a map of more than
# KICK_FULL_LANES lanes (whole-map lanes along the fewer-lane axis,
# :func:`lane_count`) gets KICKS · KICK_FULL_LANES / lanes kicks
# (kick_budget), so kicks × lanes stays bounded. The paper-like walls have
# at most 73 lanes (seeds 0–309), so they keep all KICKS; a 60 × 60 grid a
# fifth blocked at random (about 600 lanes of a few cells) gets about 100.
KICK_FULL_LANES = 100
KICK_STALL = 120
KICK_ROUNDS = 1
KICK_RELOCATE_LEN = 10
KICK_DROPS = 1
EXCHANGES = 50  # passes of stretch exchanges (.exchange) in the last straightening
# More starts: the KICK_STARTS best split-lane tours (.extra, within the
# cap after their polish; lane orders searched START_LANE_KICKS // 4 rounds).
KICK_STARTS = 1
KICK_HEAT = 30
START_LANE_KICKS = 80

# The repetition goal of issue 14 is ≤ 2 % on paper-like walls and ≤ 3 % on
# crowded ones; the default cap is the tighter one less 0.1 point (a plan
# over the cap is taken only when no candidate is under it).
MAX_REPETITION = 0.019


def _key(arr: np.ndarray, w: int, reach: int, cap: float | None, turn_weight: float) -> tuple:
    """best_plan's order: within the repetition cap, fewest turns first;
    otherwise the least repeated cells + turn_weight per turn."""
    repeats, turns = len(arr) - reach, _turns(arr, w)
    if cap is not None and repeats <= cap:
        return (0, turns, repeats)
    return (1, repeats + turn_weight * turns, 0)


def _axis_free(family: str) -> bool:
    """True when the family scores no move by the lane axis (weights 0–4 all
    zero), so its walks along rows and along columns are the same path."""
    return not any(FAMILIES[family][:5])


def best_plan(
    blocked,
    start,
    max_repetition: float | None = MAX_REPETITION,
    turn_weight: float = 0.02,
    budget_cells: int = 150_000,
    extra: bool = True,
    kicks: int = KICKS,
) -> CoveragePlan:
    """The best of several plans: the paper's pipeline (sub-regions of §3.2,
    ordered by eq. 5's depth-first walk of §3.3 or by the nearest associated
    cell of eq. 11, each swept along its fewer-turn axis, §3.4), and the
    whole map swept with each move-preference family (FAMILIES), its lanes
    along rows and along columns, with seeded tie-breaking repeated while
    the map is small (about budget_cells cells walked in all per family;
    above 20 000 reachable cells one walk of each of BIG_FAMILIES along the
    fewer-lane axis, to stay within a second on the full wall). Every
    candidate is untwisted by 2-opt (same visits, fewer turns). Choice: the
    fewest changes of heading among the plans whose repetition is at most
    ``max_repetition`` of the reachable cells (turns cost wall, eq. 3;
    repetition is the seed's figure); when none is, or with ``max_repetition=None``, the least
    repeated cells + ``turn_weight`` per turn. The winner is then
    straightened (:func:`straightened`; its last round also exchanges
    stretches, :mod:`.exchange`). On maps up to REPAIR_CELLS reachable
    cells the unused repeats are spent (:mod:`.spend`) and, with ``kicks``
    > 0, kicked at most that many times, fewer on a map of more than
    KICK_FULL_LANES lanes (:func:`kick_budget`) (:mod:`.search`, :mod:`.kick`;
    every cell covered, within the cap, no more turns; with a cap,
    KICK_DROPS repeats moved per kick and, when the plan is within the
    cap, the best split-lane tour within it a second start,
    :func:`kick_starts`). Otherwise,
    with ``extra`` (maps up to 20 000 reachable cells) more lane tours
    (:mod:`.extra`) are polished the same way (and repaired over the cap)
    and the best straightened; one replaces the plan only when its final
    key is better."""
    a, (r0, c0) = _check(blocked, start)
    h, w = a.shape
    free = np.ascontiguousarray(~a, dtype=np.uint8)
    reach_map = K.flood(free, r0 * w + c0, False)
    reach = int(reach_map.sum())
    nbr = K.neighbour_table(reach_map, False)  # shared by every walk below
    big = reach > 20_000
    # small maps: every family with its lanes along rows and along columns (the
    # fewer-lane axis of §3.4 is not always the fewer-turn one once lanes meet
    # obstacles); big maps: one walk of each of the first three families along
    # the fewer-lane axis, to stay within a second on the full wall
    axes = (None,) if big else (0, 1)
    families = BIG_FAMILIES if big else tuple(FAMILIES)
    runs = 1 if big else max(1, min(32, budget_cells // len(axes) // max(1, reach)))
    # candidates as (flat path, labels, order, axes, ms): no list of cells each
    plans = []
    walks: dict[tuple, tuple] = {}  # a walk whose moves ignore the lane axis, by its other settings
    for regions, family, seed, order, axis in [
        (True, "lanes", 0, o, None) for o in ("dfs", "nearest")
    ] + [
        (False, family, seed, "nearest", axis)
        for family in families
        for axis in axes
        for seed in range(runs)
    ]:
        t0 = time.perf_counter()
        same = (regions, family, seed, order) if not regions and _axis_free(family) else None
        if same in walks and axis is not None:  # the same path; only its stated axes differ
            path, labels, seq, ax = walks[same]
            walked = (path, labels, seq, np.full(len(ax), axis, dtype=np.int64))
        else:
            walked = _walked(
                a, (r0, c0), regions, family, seed, order, False, axis, None, reach_map, nbr
            )
            if same is not None:
                walks[same] = walked
        plans.append((*walked, (time.perf_counter() - t0) * 1e3))
    made = lane_plans(a, (r0, c0), big)
    lanes = [(_flat(p.cells, w), p.labels, p.order, p.axes, p.time_ms) for p in made]
    plans += lanes
    cap = None if max_repetition is None else max_repetition * reach
    passes = 20 if reach <= 20_000 else 2  # the winner gets more in straightened()
    moves = move_masks(free)  # for 2-opt, shared by every candidate
    scored = []
    polished: dict[bytes, tuple] = {}  # a path met before gets the same (deterministic) polish
    for i, p in enumerate(plans):
        is_lane = i >= len(plans) - len(lanes)
        done = polished.get(p[0].tobytes()) if not is_lane else None
        if done is not None:
            arr, key = done
            scored.append((key, len(scored), arr.copy(), p))
            continue
        arr = prune(free, p[0], 10)
        two_opt_masked(free, moves, arr, passes)
        key = _key(arr, w, reach, cap, turn_weight)
        if not is_lane:
            polished[p[0].tobytes()] = (arr.copy(), key)
        scored.append((key, len(scored), arr, p))
        if key[0] == 1 and cap is not None and reach <= REPAIR_CELLS and is_lane:
            # a lane tour over the cap: its repeats traded for the fewest turns
            arr = repair(free, arr, int(cap), reach)
            two_opt_masked(free, moves, arr, passes)
            scored.append((_key(arr, w, reach, cap, turn_weight), len(scored), arr, p))
    # the leaders (by their key after 2-opt) also get their stretches moved;
    # a leader equal to an earlier one would end equal too, and only a
    # strictly better key replaces the best, so it is skipped
    scored.sort(key=lambda s: (s[0], s[1]))
    best, best_key = None, None
    seen = set()
    for _, _, arr, p in scored[: RELOCATE_LEADERS if not big else BIG_LEADERS]:
        if arr.tobytes() in seen:
            continue
        seen.add(arr.tobytes())
        relocate(free, arr, RELOCATE_LEN, passes)
        arr = prune(free, arr, 10)
        key = _key(arr, w, reach, cap, turn_weight)
        if best_key is None or key < best_key:
            best, best_key = CoveragePlan(_cells(arr, w), *p[1:]), key
    window = 5 if reach <= 20_000 else 4
    spends = cap is not None and reach <= REPAIR_CELLS
    # stretches exchanged (.exchange) in the last straightening only: after
    # the spend on small maps (the spend finds more before them), never on
    # the full wall (its one plan as before)
    best = straightened(a, best, window=window, exchanges=0 if spends or big else EXCHANGES)
    if spends:  # the cap's unused repeats bought turns (.spend)
        spent = spend(free, _flat(best.cells, w), int(cap))
        best = straightened(a, replace(best, cells=_cells(spent, w)), window, exchanges=EXCHANGES)
    if reach <= REPAIR_CELLS and kicks > 0:  # iterated local search (.kick)
        moved = None if cap is None or not KICK_DROPS else int(cap)  # repeats moved too
        starts = [_flat(best.cells, w)]
        # a second start must be within the cap; when every candidate above
        # (split-lane tours among them, repaired) ended over it, as on maps
        # cut by scattered obstacles, the split tours of other seeds are not
        # built (none came within it on those maps, and they cost most of the CPU)
        within = len(starts[0]) - reach <= cap if moved is not None else False
        if within and KICK_STARTS > 0:
            starts += kick_starts(a, free, moves, reach_map, r0 * w + c0, reach, cap, passes)
        budget = kick_budget(kicks, lane_count(reach_map))
        arr = searched(
            free, starts, budget, KICK_HEAT, KICK_STALL, KICK_RELOCATE_LEN, cap=moved,
            rounds=KICK_ROUNDS, final_exchanges=EXCHANGES, drops=KICK_DROPS, until_spent=True,
        )  # fmt: skip
        return replace(best, cells=_cells(arr, w))
    if big or not extra:
        return best
    # more candidates, kept beside the ones above: more lane tours (.extra),
    # each polished as above (repaired on any map up to 20 000 cells), the
    # leaders straightened and judged on the final plan, which one replaces
    # only when better
    best_key = _key(_flat(best.cells, w), w, reach, cap, turn_weight)
    small = reach <= REPAIR_CELLS
    raw = extra_tours(
        reach_map, r0 * w + c0, EXTRA_LAMBDAS, LANE_RADIUS, small,
        exact=(LANE_TURN_RADIUS, LANE_SPAN), exact_lams=EXACT_LAMBDAS,
    )  # fmt: skip
    extras = []
    for i, tour in enumerate(raw):
        arr = polished_tour(free, moves, tour, passes, reach, cap, RELOCATE_LEN)
        extras.append((_key(arr, w, reach, cap, turn_weight), i, arr))
    extras.sort(key=lambda e: (e[0], e[1]))
    for _, idx, arr in extras[: EXTRA_LEADERS if small else EXTRA_LEADERS // 2]:
        cand = CoveragePlan(_cells(arr, w), best.labels, [], best.axes, 0.0)
        cand = straightened(a, cand, window, exchanges=EXCHANGES)
        key = _key(_flat(cand.cells, w), w, reach, cap, turn_weight)
        log.debug("extra candidate %d of %d: %s against %s", idx, len(raw), key, best_key)
        if key < best_key:
            best, best_key = cand, key
    return best


def lane_count(reach: np.ndarray) -> int:
    """Lanes of the whole map along its fewer-lane axis (§3.4): the maximal
    runs of cells where ``reach`` > 0 along rows, or along columns, whichever
    are fewer."""
    on = reach > 0
    rows = int(on[:, 0].sum() + (on[:, 1:] & ~on[:, :-1]).sum())
    cols = int(on[0].sum() + (on[1:] & ~on[:-1]).sum())
    return min(rows, cols)


def kick_budget(kicks: int, lanes: int) -> int:
    """The kicks of a map of ``lanes`` lanes (:func:`lane_count`): all
    ``kicks`` up to KICK_FULL_LANES lanes, then kicks · KICK_FULL_LANES /
    lanes (rounded down, at least one), so that kicks × lanes stays bounded."""
    if lanes <= KICK_FULL_LANES:
        return kicks
    return max(1, kicks * KICK_FULL_LANES // lanes)


def kick_starts(a, free, moves, reach_map, s0, reach, cap, passes) -> list[np.ndarray]:
    """More starts for the kicks of a small map: the split-lane tours of
    :mod:`.extra` (whole map along rows and along columns, three
    order-search seeds each; the sub-regions of §3.2 along their other
    axis), polished as best_plan's own
    candidates; of those within ``cap`` repeats, the KICK_STARTS best by
    turns, each straightened, given the cap's unused repeats (:mod:`.spend`)
    and straightened again (flat cells)."""
    w = a.shape[1]
    raw = extra_tours(
        reach_map, s0, EXTRA_LAMBDAS, LANE_RADIUS, True, kicks=START_LANE_KICKS,
        only_split=True,
    )  # fmt: skip
    ranked = []
    for i, tour in enumerate(raw):
        arr = polished_tour(free, moves, tour, passes, reach, cap, RELOCATE_LEN)
        key = _key(arr, w, reach, cap, 0.0)
        if key[0] == 0:
            ranked.append((key, i, arr))
    ranked.sort(key=lambda r: (r[0], r[1]))
    out = []
    for _, _, arr in ranked[:KICK_STARTS]:
        arr = _flat(straightened(a, _plan(arr, w), exchanges=EXCHANGES).cells, w)
        arr = spend(free, arr, int(cap))
        out.append(_flat(straightened(a, _plan(arr, w), exchanges=EXCHANGES).cells, w))
    return out


def _plan(arr: np.ndarray, w: int) -> CoveragePlan:
    return CoveragePlan(_cells(arr, w), np.zeros((0, 0), dtype=np.int32), [], np.zeros(0), 0.0)


def _flat(cells: list[tuple[int, int]], w: int) -> np.ndarray:
    return np.array([r * w + c for r, c in cells], dtype=np.int64)


def _cells(arr: np.ndarray, w: int) -> list[tuple[int, int]]:
    return list(zip((arr // w).tolist(), (arr % w).tolist(), strict=True))


def lane_plans(a: np.ndarray, start: tuple[int, int], big: bool) -> list[CoveragePlan]:
    """Lane tours (:mod:`.lanes`) of the cells reachable from ``start``: the
    whole map in lanes along rows and along columns, and the sub-regions of
    §3.2 each along its fewer-lane axis (§3.4); on big maps only the whole
    map along its fewer-lane axis (CPU on the full wall), its links of up to
    LANE_TURN_RADIUS steps priced by their turns (:mod:`.links`) and its
    order searched by BIG_KICKS local double bridges, each repaired near
    where it was made."""
    t0 = time.perf_counter()
    w = a.shape[1]
    free = np.ascontiguousarray(~a, dtype=np.uint8)
    reach = K.flood(free, start[0] * w + start[1], False)
    free = np.ascontiguousarray(reach > 0, dtype=np.uint8)
    whole = np.where(reach > 0, 0, -1).astype(np.int32)
    configs = [(whole, np.array([axis], dtype=np.int64)) for axis in (0, 1)]
    if big:
        configs = [(whole, sweep_axes(whole, 1))]
    else:
        dec = decompose(reach == 0).labels
        configs.append((dec, sweep_axes(dec, int(dec.max()) + 1)))
    configs = [(lab, ax, False) for lab, ax in configs]
    if not big and int(reach.sum()) <= REPAIR_CELLS:  # lanes cut into pieces (.lanes.split_lanes)
        configs += [(lab, ax, True) for lab, ax, _ in configs]
    s0 = start[0] * w + start[1]
    sets = [lane_set(labels, axes, s0, False, split) for labels, axes, split in configs]
    ready = prepared_sets(free, sets, LANE_RADIUS)
    out = []
    for (labels, axes, split), prepared in zip(configs, ready, strict=True):
        if prepared is None:
            continue
        kicks = 0 if big or labels is not whole else (LANE_KICKS // 4 if split else LANE_KICKS)
        exact = {}
        if big:  # one tour: its links priced by their turns, its order searched locally
            kicks = BIG_KICKS
            exact = dict(turn_radius=LANE_TURN_RADIUS, span=LANE_SPAN, local=True)
        arr = lane_tour(
            free, labels, axes, s0, LANE_LAMBDA, LANE_RADIUS, kicks=kicks, split=split,
            prepared=prepared, **exact,
        )  # fmt: skip
        out.append(CoveragePlan(_cells(arr, w), labels, [], axes, (time.perf_counter() - t0) * 1e3))
    return out


def straightened(
    blocked, plan: CoveragePlan, window: int = 5, passes: int = 5, rounds: int = 4,
    exchanges: int = 0,
) -> CoveragePlan:
    """The plan with fewer changes of heading and the same visits: windows of
    ``window`` consecutive cells are reordered when a valid order turns less
    (:func:`._kernels.straighten`), and stretches are reversed when their
    ends still join and the joins turn less (2-opt, :func:`.untwist.two_opt`),
    moved (:mod:`.relocate`) or, with ``exchanges`` passes, exchanged
    (:mod:`.exchange`); they alternate for up to ``rounds`` rounds while
    any gains (:func:`.kick.polish`)."""
    if len(plan.cells) < window + 4:
        return plan
    w = np.asarray(blocked).shape[1]
    free = np.ascontiguousarray(~np.asarray(blocked, dtype=bool), dtype=np.uint8)
    arr = np.array([r * w + c for r, c in plan.cells], dtype=np.int64)
    perms = np.array(list(itertools.permutations(range(window))), dtype=np.int64)
    removed = polish(free, arr, perms, RELOCATE_LEN, rounds, passes, exchanges)
    if removed == 0:
        return plan
    return replace(plan, cells=_cells(arr, w))


def coverage_path(
    blocked, start, max_repetition: float = MAX_REPETITION
) -> list[tuple[int, int]]:
    """The public face: a list of (row, col) from ``start``, consecutive cells
    8-adjacent, never blocked, no corner cutting, visiting every free cell
    reachable from ``start``; of :func:`best_plan`'s candidates the one with
    the fewest turns within ``max_repetition`` of the reachable cells
    (default 1.9 %). No wrap round the seam here. ValueError on a start
    outside the map or on a blocked cell."""
    return best_plan(blocked, start, max_repetition=max_repetition).cells
