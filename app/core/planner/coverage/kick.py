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

With a repetition cap the kick also moves repeats: best_plan's winner has
used its whole cap (1.9 % on the paper-like maps), spent once, greedily
(:mod:`.spend`), so the fixed-visit moves above cannot trade a repeat that
saves one turn where it stands for one that would save two elsewhere (a
notch at a staircase edge, a lane end). Each kick then also drops a
repeated visit at random (its neighbours must join by a move; the turns
may rise), and after the local moves the visits no longer needed are
pruned (:mod:`.prune`) and the room under the cap is spent again where it
saves the most turns per repeat; the result is kept on the same test
(no more turns) when it is within the cap. So the search runs over every
plan within the cap that covers every cell, not over one multiset of visits.

The local search after a kick may leave the stretch exchanges out
(``exchanges=0``: a full scan of the path per pass, about half of a
kick's CPU), so that twice as many kicks fit in the same CPU, the best plan
getting them once at the end (``final_exchanges``). :class:`Kick` is one
kick and its local search, for :mod:`.search`, which spends the kicks of
best_plan over several starts.
"""

from __future__ import annotations

import numpy as np

from . import _kernels as K
from .exchange import _apply, exchange, moves_at
from .prune import prune
from .relocate import _index, relocate
from .spend import spend
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


def droppable(free, path) -> np.ndarray:
    """Positions k (0 < k < n−1) of visits the path may drop whatever the
    turns: the cell is visited elsewhere too and p_{k−1} → p_{k+1} is a move."""
    w = free.shape[1]
    n = len(path)
    if n < 3:
        return np.zeros(0, dtype=np.int64)
    count = np.bincount(path, minlength=free.size)
    ks = np.nonzero(count[path[1:-1]] > 1)[0] + 1
    ok = [k for k in ks.tolist() if K._move_ok(free, path[k - 1], path[k + 1], w)]
    return np.array(ok, dtype=np.int64)


def kicked(
    free, path, kicks, perms, relocate_len, moves=2, floor=-4, seed=0, tries=50,
    cap=None, drops=1, exchanges=50, final_exchanges=0,
) -> np.ndarray:
    """The path after ``kicks`` rounds of iterated local search (see the
    module); a new array with at most as many turns. Without ``cap`` the
    visits are the same; with ``cap`` (repeated visits allowed) each kick
    also drops ``drops`` repeated visits at random (:func:`droppable`) and,
    after the local moves, the unneeded visits go (:mod:`.prune`) and the
    room under the cap (or under the input's own repeats, when more) is
    spent where it saves the most turns (:mod:`.spend`): the repeats move
    to where they buy the most. Every cell stays covered."""
    w = free.shape[1]
    rng = np.random.default_rng(seed)
    best = np.ascontiguousarray(path, dtype=np.int64).copy()
    best_turns = _turns(best, w)
    if len(best) < 6:
        return best
    kick = Kick(free, [best], cap, perms, relocate_len, moves, floor, tries, drops, exchanges)
    for _ in range(kicks):
        cur, turns = kick(best, rng)
        if turns is not None and turns <= best_turns:
            best, best_turns = cur, turns
    if final_exchanges and not exchanges:  # the local search skipped them: once at the end
        polish(free, best, perms, relocate_len, exchanges=final_exchanges)
    return best


class Kick:
    """One kick and its local search (see the module), with the buffers it
    reuses: ``kick(path, rng)`` is (the new path, its turns), the turns
    None when its repeats are over the limit (the cap, or the most repeats
    among ``paths``, when more). ``rounds``: of the local moves
    (:func:`polish`); ``until_spent``: the spend stops once the repeats
    reach the limit (:func:`.spend.spend`; the plain reversals it would
    go on to take are 2-opt's, in the local moves after it)."""

    def __init__(
        self, free, paths, cap, perms, relocate_len, moves=2, floor=-4, tries=50, drops=1,
        exchanges=50, rounds=4, until_spent=False,
    ):  # fmt: skip
        self.free, self.w = free, free.shape[1]
        self.perms, self.relocate_len, self.rounds = perms, relocate_len, rounds
        self.moves, self.floor, self.tries, self.drops = moves, floor, tries, drops
        self.exchanges, self.until_spent = exchanges, until_spent
        self.distinct = len(np.unique(paths[0]))
        # the repeats allowed: the cap, or the input's own when it is over the cap
        own = max(len(p) - self.distinct for p in paths)
        self.limit = None if cap is None else max(int(cap), own)
        size = max(len(p) for p in paths) + 2 * (self.limit or 0) + 8
        self.first = np.full(free.size, -1, dtype=np.int64)
        self.nxt = np.empty(size, dtype=np.int64)
        self.tmp = np.empty(size, dtype=np.int64)
        self.out = np.zeros((4096, 4), dtype=np.int64)

    def __call__(self, path, rng):
        free, w, limit = self.free, self.w, self.limit
        cur = path.copy()
        n = len(cur)
        for _ in range(self.moves):
            _index(cur, n, self.first, self.nxt)
            for _ in range(self.tries):
                i = int(rng.integers(1, n - 3))
                m = moves_at(free, cur, n, w, i, self.first, self.nxt, self.out, self.floor)
                if m:
                    j, k, kind, _ = self.out[int(rng.integers(m))]
                    _apply(cur, n, i, int(j), int(k), int(kind), self.tmp)
                    break
        if limit is not None:  # visits moved too: a repeat dropped, the cap's room spent again
            for _ in range(self.drops):
                ks = droppable(free, cur)
                if len(ks):
                    k = int(ks[int(rng.integers(len(ks)))])
                    cur = np.concatenate((cur[:k], cur[k + 1 :]))
        polish(free, cur, self.perms, self.relocate_len, self.rounds, exchanges=self.exchanges)
        if limit is not None:
            cur = prune(free, cur, 10)
            room = limit - (len(cur) - self.distinct)
            if room > 0:
                spent = spend(free, cur, limit, 1.0, room + 2, self.until_spent)
                if len(spent) != len(cur):
                    cur = spent
                    polish(
                        free, cur, self.perms, self.relocate_len, self.rounds,
                        exchanges=self.exchanges,
                    )  # fmt: skip
            if len(cur) - self.distinct > limit:
                return cur, None
        return cur, _turns(cur, w)
