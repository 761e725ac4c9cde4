"""The kicks of a small map spent where they still gain: iterated local
search from several starts, each run until it stagnates.

The race this replaces kicked each start a fixed few times and gave every
other kick to the one that then turned least; but a search's early lead
says little about where it ends (on paper-like map 201 the split-lane
start led after 30 kicks and stalled at 169 turns, while the winner's own
search, left behind, ends at 151–156 from any seed), and a fixed count
stops searches that still gain as soon as ones that stalled long ago.

Here every start is a *run* of iterated local search (:class:`.kick.Kick`:
random stretch exchanges, a repeat dropped, the local moves, the cap's
room spent again; a kicked plan is kept when it turns no more than the
run's best). Each run first gets ``heat`` kicks. Then, kick by kick, the
live run whose best turns least gets the next kick; a run is *stalled*
once ``stall`` kicks in a row have not lowered its turns, and stops being
kicked. The search ends when every run has stalled or ``budget`` kicks are
spent. So a run that leads but stalls hands the kicks on to the next-best
start instead of keeping them (restarts on stagnation, Lourenço, Martin &
Stützle's iterated local search), and a map whose search converges early
costs fewer kicks. Every kick keeps every cell covered and the repeats
within the cap (Definition 7); fewer turns: seed 001 eq. 3. The kicks are
seeded: a plan is reproducible.
"""

from __future__ import annotations

import numpy as np

from .kick import Kick, _turns, polish


def searched(
    free, starts, budget, heat, stall, relocate_len, cap=None, seed=0, rounds=1,
    final_exchanges=50, **kw,
) -> np.ndarray:
    """The plan with the fewest turns found by iterated local search from
    ``starts`` (flat cells, each complete, within ``cap`` repeats), at most
    ``budget`` kicks in all (see the module): each start ``heat`` kicks,
    then the live run with the fewest turns kicked until ``stall`` kicks
    in a row gain nothing; ``rounds`` of local moves per kick, ``kw`` for
    :class:`.kick.Kick`; the best then gets ``final_exchanges`` passes of
    stretch exchanges. Ties go to the earlier start."""
    w = free.shape[1]
    paths = [np.ascontiguousarray(s, dtype=np.int64).copy() for s in starts]
    if min(len(p) for p in paths) < 6:
        return min(paths, key=lambda p: _turns(p, w))
    kick = Kick(free, paths, cap, None, relocate_len, rounds=rounds, exchanges=0, **kw)
    runs = [
        dict(best=p, turns=_turns(p, w), idle=0, rng=np.random.default_rng(seed + i))
        for i, p in enumerate(paths)
    ]
    used = 0

    def step(run) -> None:
        cur, turns = kick(run["best"], run["rng"])
        if turns is not None and turns <= run["turns"]:
            run["idle"] = 0 if turns < run["turns"] else run["idle"] + 1
            run["best"], run["turns"] = cur, turns
        else:
            run["idle"] += 1

    for run in runs:
        for _ in range(min(heat, budget - used)):
            step(run)
            used += 1
    while used < budget:
        live = [r for r in runs if r["idle"] < stall]
        if not live:
            break
        step(min(live, key=lambda r: r["turns"]))
        used += 1
    best = min(runs, key=lambda r: r["turns"])["best"]
    if final_exchanges:  # the kicks' local search skipped them: once at the end
        polish(free, best, None, relocate_len, exchanges=final_exchanges)
    return best
