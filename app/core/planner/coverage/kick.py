"""Iterated local search on the final plan: kicks by stretch exchanges.

The moves that keep every visit (2-opt reversals, :mod:`.untwist`; stretches
moved, :mod:`.relocate`; stretches exchanged, :mod:`.exchange`; windows
reordered, :func:`._kernels.straighten`) stop in a local optimum of the turn
count. Here the plan is kicked out of it (Lourenço, Martin & Stützle's
iterated local search, with exchanges as the kick in place of the double
bridge of tour improvement): ``moves`` random valid exchanges, each adding
at most ``-floor`` turns, then the local moves again; the result is kept
when it turns no more than the best so far (equal plans are taken, so the
search walks across plateaus). The kicks are drawn from a seeded
generator, so a plan is reproducible. Every move keeps the multiset of
visited cells, so coverage and repetition (Definition 7) stay exactly as
they were, and every join is a move (8-adjacent, no corner cutting); the
first cell stays first. Fewer turns: seed 001 eq. 3 (every turn leaves
S_UR of wall unprobed). No wrap.
"""

from __future__ import annotations

import numpy as np

from . import _kernels as K
from .exchange import _apply, exchange, moves_at
from .relocate import _index, relocate
from .untwist import two_opt


def _turns(arr: np.ndarray, w: int) -> int:
    dr, dc = np.diff(arr // w), np.diff(arr % w)
    return int(((dr[1:] != dr[:-1]) | (dc[1:] != dc[:-1])).sum())


def polish(free, arr, perms, relocate_len, rounds=4, passes=5, exchanges=50) -> int:
    """The local moves in turn while any gains (``perms``: the window
    orders of :func:`._kernels.straighten`, or None to skip it; stretches
    exchanged in ``exchanges`` passes, 0 to skip); returns the turns
    removed. ``arr`` is changed in place."""
    removed = 0
    for _ in range(rounds):
        gained = (
            (K.straighten(free, arr, perms, passes) if perms is not None else 0)
            + two_opt(free, arr, 50)
            + relocate(free, arr, relocate_len, 50)
            + (exchange(free, arr, exchanges) if exchanges else 0)
        )
        removed += gained
        if gained == 0:
            break
    return removed


def kicked(
    free, path, kicks, perms, relocate_len, moves=2, floor=-4, seed=0, tries=50
) -> np.ndarray:
    """The path after ``kicks`` rounds of iterated local search (see the
    module); a new array with the same visits and at most as many turns."""
    w = free.shape[1]
    n = len(path)
    rng = np.random.default_rng(seed)
    best = np.ascontiguousarray(path, dtype=np.int64).copy()
    best_turns = _turns(best, w)
    if n < 6:
        return best
    first = np.full(free.size, -1, dtype=np.int64)
    nxt = np.empty(n, dtype=np.int64)
    tmp = np.empty(n, dtype=np.int64)
    out = np.zeros((4096, 4), dtype=np.int64)
    for _ in range(kicks):
        cur = best.copy()
        for _ in range(moves):
            _index(cur, n, first, nxt)
            for _ in range(tries):
                i = int(rng.integers(1, n - 3))
                m = moves_at(free, cur, n, w, i, first, nxt, out, floor)
                if m:
                    j, k, kind, _ = out[int(rng.integers(m))]
                    _apply(cur, n, i, int(j), int(k), int(kind), tmp)
                    break
        polish(free, cur, perms, relocate_len)
        turns = _turns(cur, w)
        if turns <= best_turns:
            best, best_turns = cur, turns
    return best
