"""Leaving a dead zone by the path selection function (seed 001 §3.4).

Definition 4: the robot is in a dead zone when every neighbour is a
boundary, an obstacle or already covered. It then steers by

    y_i = cos Δφ_i                                  (eq. 6)
    Δφ_i = φ_T − θ_i                                (eq. 7)
    f_i = x_i + t·y_i,   0 < t < 1                  (eq. 8)
    U = argmax_i f_i over the k neighbours          (eq. 9)

where φ_T is the bearing from the robot's cell P to the nearest uncovered
cell U, θ_i the bearing from P to neighbour i, and x_i the cell state of
eq. 4. Eq. 7 is printed with arctan|Δy/Δx|, which cannot tell left from
right; Table 1's values need the full bearings (atan2), e.g. at (3D, 10D)
the cell to the left has f = −0.12 = 0 + 0.5·cos(180° − (−76°)). So the
bearings here are atan2(Δy, Δx), with x the column and y the row (up).

The robot counts its own cell as visited once more on arrival (Table 1: the
cell it just left has x = −1 after its second visit).
"""

from __future__ import annotations

import math

import numpy as np

# Table 1's rows, as (dx, dy) in the paper's (x, y).
TABLE1_NEIGHBOURS = ((1, 1), (1, 0), (1, -1), (0, 1), (0, -1), (-1, 1), (-1, 0), (-1, -1))


def direction_function(p: tuple[int, int], nxt: tuple[int, int], target: tuple[int, int]) -> float:
    """y_i of eqs. 6–7 for cells given as (x, y): cos of the angle between
    P→N_i and P→U."""
    phi_t = math.atan2(target[1] - p[1], target[0] - p[0])
    theta = math.atan2(nxt[1] - p[1], nxt[0] - p[0])
    return math.cos(phi_t - theta)


def nearest_uncovered(
    blocked: np.ndarray, visits: np.ndarray, rc: tuple[int, int]
) -> tuple[int, int] | None:
    """(row, col) of the uncovered free cell nearest to ``rc`` (Euclidean, as
    the paper's U), least row then column on ties; None when all are covered."""
    open_ = np.argwhere(~np.asarray(blocked, dtype=bool) & (np.asarray(visits) == 0))
    if len(open_) == 0:
        return None
    d2 = (open_[:, 0] - rc[0]) ** 2 + (open_[:, 1] - rc[1]) ** 2
    i = int(np.argmin(d2))
    return int(open_[i, 0]), int(open_[i, 1])


def selection_values(
    blocked: np.ndarray,
    visits: np.ndarray,
    rc: tuple[int, int],
    target: tuple[int, int],
    t: float = 0.5,
) -> dict[tuple[int, int], float]:
    """f_i (eq. 8) of every neighbour of ``rc`` on the map, keyed by (dx, dy)
    in the paper's axes (x = column, y = row): −∞ on obstacles."""
    if not 0.0 < t < 1.0:
        raise ValueError(f"t must lie in (0, 1), got {t}")
    blocked = np.asarray(blocked, dtype=bool)
    rows, cols = blocked.shape
    r, c = rc
    out: dict[tuple[int, int], float] = {}
    for dx, dy in TABLE1_NEIGHBOURS:
        nr, nc = r + dy, c + dx
        if not (0 <= nr < rows and 0 <= nc < cols):
            continue
        if blocked[nr, nc]:
            out[(dx, dy)] = -math.inf
            continue
        x_i = 1.0 - float(visits[nr, nc])  # eq. 4
        y = direction_function((c, r), (nc, nr), (target[1], target[0]))
        out[(dx, dy)] = x_i + t * y
    return out


def escape(
    blocked: np.ndarray,
    visits: np.ndarray,
    rc: tuple[int, int],
    t: float = 0.5,
    corner_cutting: bool = False,
    target: tuple[int, int] | None = None,
    max_steps: int | None = None,
) -> list[tuple[int, int]] | None:
    """Steps out of a dead zone by eq. 9 until an uncovered cell (or
    ``target``, the next region's entry cell in §4) is reached.

    ``visits`` is updated in place (the robot's own cell is counted again on
    arrival). The paper treats the robot as a point and lets it cut corners
    (Table 1's last step passes a blocked cell diagonally); with
    corner_cutting False such moves are not candidates. Returns the cells
    stepped to, or None when the greedy rule stalls (it has no memory, so it
    can oscillate in a pocket) within ``max_steps``."""
    blocked = np.asarray(blocked, dtype=bool)
    rows, cols = blocked.shape
    limit = max_steps if max_steps is not None else 4 * (rows + cols)
    path: list[tuple[int, int]] = []
    r, c = rc
    for _ in range(limit):
        goal = target if target is not None else nearest_uncovered(blocked, visits, (r, c))
        if goal is None or (r, c) == goal:
            return path
        f = selection_values(blocked, visits, (r, c), goal, t)
        best, best_f = None, -math.inf
        for dx, dy in TABLE1_NEIGHBOURS:
            v = f.get((dx, dy), -math.inf)
            if v == -math.inf:
                continue
            if not corner_cutting and dx and dy and (blocked[r + dy, c] or blocked[r, c + dx]):
                continue
            if v > best_f:
                best, best_f = (dx, dy), v
        if best is None:
            return None
        r, c = r + best[1], c + best[0]
        first = visits[r, c] == 0
        visits[r, c] += 1
        path.append((r, c))
        if first and target is None:
            return path
        if target is not None and (r, c) == target:
            return path
    return None


__all__ = ["direction_function", "escape", "nearest_uncovered", "selection_values"]
