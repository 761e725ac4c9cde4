"""search (coverage/search.py): the kicks of a small map spread over
several starts, each run kicked until it stalls; every plan complete,
valid and within the cap."""

import numpy as np
import pytest

from app.core.planner.coverage import figures
from app.core.planner.coverage import search as search_module
from app.core.planner.coverage.kick import _turns
from app.core.planner.coverage.plan import MAX_REPETITION, best_plan, plan_coverage
from app.core.planner.coverage.search import searched
from bench.coverage_anchors import bcd
from bench.coverage_maps import paper_like, start_cell

from .conftest import free_cell, random_grid
from .test_coverage_path import check, reachable


def _flat(cells, w):
    return np.array([r * w + c for r, c in cells], dtype=np.int64)


def _cells(arr, w):
    return list(zip((arr // w).tolist(), (arr % w).tolist(), strict=True))


def test_searched_plans_stay_complete_valid_and_within_the_cap(rng):
    for density in (0.0, 0.2):
        for _ in range(3):
            h, w = int(rng.integers(4, 12)), int(rng.integers(4, 12))
            blocked = random_grid(rng, h, w, density)
            start = free_cell(rng, blocked)
            if start is None:
                continue
            starts = [
                _flat(plan_coverage(blocked, start, regions=False, family=f).cells, w)
                for f in ("lanes", "tight")
            ]
            cap = max(len(p) - len(np.unique(p)) for p in starts)
            free = np.ascontiguousarray(~blocked, dtype=np.uint8)
            out = searched(free, starts, 12, 3, 4, 10, cap=cap, until_spent=True)
            cells = _cells(out, w)
            assert check(blocked, start, cells) == reachable(blocked, start)
            got = figures(blocked, start, cells)
            assert got.visits - got.covered <= cap
            assert got.turns <= min(_turns(p, w) for p in starts)
            again = searched(free, starts, 12, 3, 4, 10, cap=cap, until_spent=True)
            assert again.tolist() == out.tolist()  # seeded: reproducible


class _Scripted:
    """A stand-in for kick.Kick: each start's path is a row of cells, and a
    kick of it turns as its script says (start 0 stuck at its first value,
    start 1 gaining a turn per kick), so the runs' order is known."""

    script = {0: 100, 1: 120}

    def __init__(self, free, paths, cap, perms, relocate_len, **kw):
        self.kicked = {0: 0, 1: 0}

    def __call__(self, path, rng):
        who = int(path[0])
        self.kicked[who] += 1
        turns = self.script[who] if who == 0 else 120 - self.kicked[who]
        return path.copy(), turns


def test_a_stalled_lead_hands_its_kicks_to_the_next_start(monkeypatch):
    # start 0 leads after the heat (100 turns against 119) but never gains;
    # once it has stalled the kicks go to start 1, which ends below it (a
    # race giving every kick to the early lead would end at 100)
    monkeypatch.setattr(search_module, "Kick", _Scripted)
    monkeypatch.setattr(search_module, "_turns", lambda p, w: 100 if p[0] == 0 else 120)
    free = np.ones((1, 8), dtype=np.uint8)
    starts = [np.arange(0, 8, dtype=np.int64), np.arange(1, 8, dtype=np.int64)]
    out = searched(free, starts, 60, 1, 5, 10, final_exchanges=0)
    assert out[0] == 1  # start 1's run
    # and with a budget too small to outlast the lead's stall, the lead's
    out = searched(free, starts, 6, 1, 5, 10, final_exchanges=0)
    assert out[0] == 0


@pytest.mark.parametrize("seed", [
    # tuning map 101: BCD turns 184 times at 18 % repetition; the winner and
    # its kicks alone stayed above it (195), a second start for the kicks (a
    # split-lane tour) brings it below
    101,
    # tuning map 209 (held out once): its single start stopped at 222 turns
    # after a fixed 170 kicks (BCD 212) though its search was still gaining;
    # kicked until it stalls it ends below. (Map 201's failure, an early lead
    # that stalled at 169 against BCD's 159, is the scheduling above.)
    209,
])
def test_paper_like_map_turns_less_than_bcd(seed):
    blocked = paper_like(seed)
    start = start_cell(blocked)
    cells = best_plan(blocked, start).cells
    got = figures(blocked, start, cells)
    assert check(blocked, start, cells) == reachable(blocked, start)
    assert got.visits - got.covered <= MAX_REPETITION * got.reachable
    assert got.turns < figures(blocked, start, bcd(blocked, start)).turns
