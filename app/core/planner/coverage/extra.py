"""More lane tours for best_plan, kept beside its own candidates.

The lane order of a tour (:mod:`.lanes`) minimises the links' cost, but the
plan that best_plan returns is that tour after pruning, repair under the
repetition cap, 2-opt, or-opt and straightening, and its turns follow the
link cost only loosely: a lower-cost order can end with more turns. So the
tours here are never put in place of best_plan's own; each is polished the
same way and judged on the final plan's turns (then its repeats), and
best_plan keeps whichever final plan is better — extra search can only
make a plan better.

The tours (seed 001 §3.4: sweep each region along its fewer-turn axis;
eq. 3: each turn leaves wall unprobed):

- the whole map in lanes along rows and along columns (on larger maps only
  along its fewer-lane axis, for CPU), their order searched longer
  (``kicks`` rounds of iterated local search) from other random seeds;
- the sub-regions of §3.2, each in lanes along its other axis;
- on small maps each of these also with lanes cut beside their neighbours'
  ends (:func:`.lanes.split_lanes`).
- with ``exact``, each of these once more with its short links priced by
  their fewest turns (:mod:`.links`) and its order searched by local
  double bridges.

Each is built at each link cost of ``lams`` (turns per cell crossed).
best_plan repairs these tours over the repetition cap (:mod:`.repair`) on
every map it gives them to, not only on the small ones: on crowded walls
that is what brings most of them within the cap.
"""

from __future__ import annotations

import numpy as np

from .decompose import decompose
from .lanes import lane_set, lane_tour, prepared_sets
from .prune import prune
from .relocate import relocate
from .repair import repair
from .sweep import sweep_axes
from .untwist import two_opt_masked

EXTRA_KICKS = 160  # rounds of iterated local search per extra whole-map tour
EXTRA_SEEDS = (2, 3, 4)  # random seeds of those searches (best_plan's own uses 1)


def extra_tours(
    reach: np.ndarray,
    start: int,
    lams: tuple[float, ...],
    radius: int,
    split: bool,
    kicks: int = EXTRA_KICKS,
    seeds: tuple[int, ...] = EXTRA_SEEDS,
    exact: tuple[int, int] = (0, 0),
    exact_lams: tuple[float, ...] = (),
    only_split: bool = False,
) -> list[np.ndarray]:
    """Lane tours (flat cells from ``start``) of the cells where ``reach``
    > 0 (the flood from the start): see the module's docstring. ``split``:
    also the tours of lanes cut beside their neighbours' ends. ``exact`` =
    (turn radius, span), radius > 0: each tour also once more with its
    links of up to that many steps priced by their fewest turns
    (:mod:`.links`) and its order searched by double bridges of at most
    ``span`` lanes (:func:`.lanes.kicked_t`), at each link cost of
    ``exact_lams`` (``lams`` when empty). ``only_split`` (with ``split``):
    only the tours of split lanes (the second start of best_plan's kicks, :mod:`.search`)."""
    free = np.ascontiguousarray(reach > 0, dtype=np.uint8)
    whole = np.where(reach > 0, 0, -1).astype(np.int32)
    dec = decompose(reach == 0).labels
    count = int(dec.max()) + 1
    own = sweep_axes(dec, count)
    configs = [
        (whole, np.array([axis], dtype=np.int64), seed, la)
        for axis in ((0, 1) if split else tuple(sweep_axes(whole, 1)))
        for seed in seeds
        for la in lams
    ]  # fmt: skip
    configs += [(dec, 1 - own, 0, la) for la in lams]
    configs = [(lab, ax, s, la, False, (0, 0)) for lab, ax, s, la in configs]
    if split:
        configs += [(lab, ax, s, la, True, ex) for lab, ax, s, la, _, ex in configs]
    if exact[0] > 0:
        configs += [
            (lab, ax, s, la, sp, exact)
            for lab, ax, s, la0, sp, _ in configs
            for la in (exact_lams or (la0,))
            if la0 == lams[0]
        ]
    if split and only_split:
        configs = [c for c in configs if c[4]]
    sets = {}
    for lab, ax, _, _, sp, _ in configs:
        k = (id(lab), ax.tobytes(), sp)
        if k not in sets:
            sets[k] = lane_set(lab, ax, start, False, sp)
    ready = dict(zip(sets, prepared_sets(free, list(sets.values()), radius), strict=True))
    out = []
    for lab, ax, seed, la, sp, (turn_radius, span) in configs:
        k = (id(lab), ax.tobytes(), sp)
        if ready[k] is None:
            continue
        lanes, first, dist = ready[k]
        n_kicks = (kicks // 4 if sp else kicks) if seed > 0 else 0
        out.append(
            lane_tour(
                free, lab, ax, start, la, radius, kicks=n_kicks, seed=max(seed, 1), split=sp,
                prepared=([ln.copy() for ln in lanes], first, dist),
                turn_radius=turn_radius, span=span,
            )  # fmt: skip
        )
    return out


def polished_tour(free, moves, arr, passes, reach, cap, relocate_len) -> np.ndarray:
    """best_plan's polish of one lane tour (flat cells): pruned
    (:mod:`.prune`), untwisted by 2-opt (:mod:`.untwist`, ``moves`` its
    masks of ``free``), when over ``cap`` repeated visits (None: no cap)
    repaired (:mod:`.repair`) and untwisted again, its stretches up to
    ``relocate_len`` cells moved (:mod:`.relocate`) and pruned again. Same
    cells covered; ``reach`` is their count."""
    arr = prune(free, arr, 10)
    two_opt_masked(free, moves, arr, passes)
    if cap is not None and len(arr) - reach > cap:
        arr = repair(free, arr, int(cap), reach)
        two_opt_masked(free, moves, arr, passes)
    relocate(free, arr, relocate_len, passes)
    return prune(free, arr, 10)
