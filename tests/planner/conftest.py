import heapq
import math

import numpy as np
import pytest

SQ2 = math.sqrt(2.0)


def dijkstra_length(blocked: np.ndarray, start, goal):
    """Plain Dijkstra with the Moving AI cost model, written independently of
    the planners: 8 moves, diagonal only when both orthogonal cells are free."""
    h, w = blocked.shape
    dist = {start: 0.0}
    heap = [(0.0, start)]
    done = set()
    while heap:
        d, (r, c) = heapq.heappop(heap)
        if (r, c) in done:
            continue
        done.add((r, c))
        if (r, c) == goal:
            return d
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                if dr == 0 and dc == 0:
                    continue
                nr, nc = r + dr, c + dc
                if not (0 <= nr < h and 0 <= nc < w) or blocked[nr, nc]:
                    continue
                if dr and dc and (blocked[r + dr, c] or blocked[r, c + dc]):
                    continue
                nd = d + (SQ2 if dr and dc else 1.0)
                if nd < dist.get((nr, nc), math.inf):
                    dist[(nr, nc)] = nd
                    heapq.heappush(heap, (nd, (nr, nc)))
    return None


def random_grid(rng, h, w, density):
    return rng.random((h, w)) < density


def free_cell(rng, blocked):
    free = np.argwhere(~blocked)
    r, c = free[rng.integers(len(free))]
    return int(r), int(c)


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
