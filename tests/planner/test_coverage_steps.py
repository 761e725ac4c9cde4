"""Each step of the seed 001 coverage planner on constructed grids."""

import json
import math

import numpy as np
import pytest

from app.core.planner.coverage import _kernels as K
from app.core.planner.coverage.decompose import decompose, m_n_points, obstacle_boxes
from app.core.planner.coverage.escape import escape, selection_values
from app.core.planner.coverage.order import (
    PAPER_MATRIX,
    PAPER_ORDER,
    adjacency_matrix,
    dfs_order,
)
from app.core.planner.coverage.sweep import (
    CrawlerDims,
    boustrophedon,
    count_turns,
    lane_counts,
    sweep_axes,
    turn_gap_m,
    turn_missed_area_m2,
)
from app.core.planner.coverage.switch import (
    associated_cells,
    exit_cell,
    nearest_entry,
    switch_path,
)
from app.core.planner.coverage.wall import (
    Band,
    Disc,
    WallSpec,
    cell_states,
    default_wall,
    load_wall,
    neighbours,
    rasterise,
)

# ---- the wall grid (§3.1, eq. 4) -----------------------------------------------------


def test_default_wall_is_the_unrolled_24m_tank():
    spec = default_wall()
    blocked = rasterise(spec)
    assert blocked.shape == (96, round(math.pi * 24.0 / 0.1))  # ≈ 72 000 cells
    r, c = int(0.9 / 0.1), int(3.0 / 0.1)  # first manhole's centre
    assert blocked[r, c]
    assert 0.02 < blocked.mean() < 0.2


def test_cell_states_eq4():
    blocked = np.array([[False, True, False]])
    visits = np.array([[0, 0, 3]])
    x = cell_states(blocked, visits)
    assert x[0, 0] == 1 and x[0, 1] == -math.inf and x[0, 2] == 1 - 3


def _seam_wall(crossable):
    # 3 m round, 1 m high, a seam from bottom to top at x = 1.5 m
    return WallSpec(3.0 / math.pi, 1.0, 0.1, seams=(Band(1.5, 0.0, 1.5, 1.0, 0.01, crossable),))


def test_a_seam_not_to_cross_splits_the_wall_unless_it_wraps_round():
    blocked = rasterise(_seam_wall(crossable=False))
    free = np.ascontiguousarray(~blocked, dtype=np.uint8)
    w = blocked.shape[1]
    left = K.flood(free, 5 * w + 2, False)
    assert left[5, 2] and not left[5, w - 3]
    around = K.flood(free, 5 * w + 2, True)
    assert around[5, w - 3]
    assert not rasterise(_seam_wall(crossable=True)).any()


def test_neighbours_cross_the_seam_only_with_wrap():
    blocked = np.zeros((3, 5), dtype=bool)
    assert (1, 4) in neighbours(blocked, 1, 0, wrap=True)
    assert (1, 4) not in neighbours(blocked, 1, 0, wrap=False)
    blocked[0, 1] = True
    around = neighbours(blocked, 1, 1)
    assert (0, 1) not in around and (1, 0) in around and (2, 2) in around
    # diagonals past the blocked cell would cut its corner
    assert (0, 0) not in around and (0, 2) not in around
    assert (0, 3) in neighbours(blocked, 1, 2) or blocked[0, 3]


def test_stair_band_wraps_past_the_seam():
    spec = WallSpec(4.0 / math.pi, 1.0, 0.1, stairs=(Band(3.5, 0.0, 4.5, 1.0, 0.2),))
    blocked = rasterise(spec)
    assert blocked[0, 35] and blocked[9, 4]


def test_load_wall_from_toml_and_json(tmp_path):
    toml = tmp_path / "wall.toml"
    toml.write_text(
        "[wall]\ndiameter_m = 10.0\nheight_m = 4.0\n"
        "[[wall.manholes]]\nx_m = 2.0\ny_m = 1.0\ndiameter_m = 0.6\n"
    )
    spec = load_wall(toml)
    assert spec.diameter_m == 10.0 and spec.manholes == (Disc(2.0, 1.0, 0.6),)
    js = tmp_path / "wall.json"
    js.write_text(
        json.dumps({"height_m": 2.0, "seams": [{"x0_m": 0, "y0_m": 1, "x1_m": 3, "y1_m": 1}]})
    )
    assert load_wall(js).seams[0].x1_m == 3
    js.write_text(json.dumps({"height_m": 2.0, "nozzles": [{"x": 1}]}))
    with pytest.raises(ValueError, match="nozzles\\[0\\]"):
        load_wall(js)
    js.write_text(json.dumps({"cell_m": 0}))
    with pytest.raises(ValueError, match="cell_m"):
        load_wall(js)


# ---- rectangle decomposition (§3.2) ---------------------------------------------------


def test_m_and_n_points():
    # an L: column 2 rows 1..4, row 1 columns 2..5
    cells = np.array([(r, 2) for r in range(1, 5)] + [(1, c) for c in range(3, 6)])
    m, n = m_n_points(cells)
    assert m == (2, 1)  # least x, least y among ties
    assert n == (5, 1)


def test_one_box_in_the_middle_gives_three_monotone_regions():
    blocked = np.zeros((10, 12), dtype=bool)
    blocked[3:6, 4:7] = True
    dec = decompose(blocked)
    lab = dec.labels
    assert dec.count == 3
    assert (lab[blocked] == -1).all() and (lab[~blocked] >= 0).all()
    left, top, low = lab[0, 0], lab[9, 8], lab[0, 8]
    assert len({left, top, low}) == 3
    assert (lab[:, :4] == left).all()  # the vertical cut at M's column
    assert (lab[6:, 4:] == top).all()  # the horizontal cut above N's row
    assert lab[2, 5] == low and lab[5, 9] == low  # under and right of the box
    rows, cols = lane_counts(lab, dec.count)
    for k in range(dec.count):
        rr, cc = np.nonzero(lab == k)
        # monotone both ways: one run per row and per column
        assert rows[k] == len(set(rr.tolist())) and cols[k] == len(set(cc.tolist()))


def test_diagonal_band_is_split_into_tight_boxes():
    blocked = np.zeros((40, 40), dtype=bool)
    for i in range(40):
        blocked[i, max(0, i - 1) : i + 1] = True
    boxes = obstacle_boxes(blocked)
    assert len(boxes) > 4
    covered = sum((b.y1 - b.y0 + 1) * (b.x1 - b.x0 + 1) for b in boxes)
    assert covered < 0.3 * 40 * 40  # one box would hold the whole map
    dec = decompose(blocked)
    assert (dec.labels[~blocked] >= 0).all()  # no free cell given up


# ---- sub-region order (eq. 5, §3.3) ------------------------------------------------------


def test_paper_example_order_from_its_matrix():
    assert dfs_order(PAPER_MATRIX, 0) == list(PAPER_ORDER)  # ①→③→②→④→⑥→⑦→⑤


def test_dfs_steps_back_when_a_vertex_has_no_unvisited_neighbour():
    inf = math.inf
    # 0 — 1 — 2 and 0 — 3 (farther): from 2 it must back up to 0 to reach 3
    a = np.array([[0, 1, inf, 5], [1, 0, 1, inf], [inf, 1, 0, inf], [5, inf, inf, 0]], dtype=float)
    assert dfs_order(a, 0) == [0, 1, 2, 3]
    assert dfs_order(a, 3) == [3, 0, 1, 2]


def test_adjacency_matrix_of_a_decomposition():
    blocked = np.zeros((10, 12), dtype=bool)
    blocked[3:6, 4:7] = True
    dec = decompose(blocked)
    a = adjacency_matrix(dec.labels, dec.count)
    assert np.allclose(np.diag(a), 0) and np.array_equal(a, a.T)
    assert np.isfinite(a).all()  # all three regions touch each other
    blocked2 = np.zeros((5, 9), dtype=bool)
    blocked2[:, 4] = True
    blocked2[2, 4] = False
    dec2 = decompose(blocked2)
    a2 = adjacency_matrix(dec2.labels, dec2.count)
    assert (~np.isfinite(a2)).any()


# ---- sweeps and turns (eqs. 2–3, §3.4) ---------------------------------------------------


def test_turn_gap_and_missed_area_follow_eqs_2_and_3():
    dims = CrawlerDims()
    a = dims.inner_s_m / 2 + dims.wheel_d_m + dims.overhang_m + dims.probe_ahead_m
    i = turn_gap_m(dims)
    assert (i + a) ** 2 == pytest.approx(dims.probe_width_m**2 + a**2)
    s_ur = turn_missed_area_m2(dims)
    assert 0 < s_ur < (dims.length_m + 2 * i) * dims.probe_width_m
    # a longer body turns closer to the boundary and misses more of it
    longer = CrawlerDims(length_m=0.4)
    assert turn_gap_m(longer) < i


@pytest.mark.parametrize("axis", [0, 1])
@pytest.mark.parametrize("size", [(4, 7), (5, 6), (3, 3)])
@pytest.mark.parametrize("corner", [0, 1, 2, 3])
def test_boustrophedon_covers_a_rectangle_once_and_ends_at_exit_cell(axis, size, corner):
    h, w = size
    rect = (2, 2 + h - 1, 5, 5 + w - 1)
    y0, y1, x0, x1 = rect
    entry = [(y0, x0), (y0, x1), (y1, x1), (y1, x0)][corner]
    cells = boustrophedon(y0, y1, x0, x1, entry, axis)
    assert cells[0] == entry and len(cells) == len(set(cells)) == h * w
    for (r0, c0), (r1, c1) in zip(cells, cells[1:], strict=False):
        assert abs(r1 - r0) + abs(c1 - c0) == 1
    lanes = h if axis == 0 else w
    assert count_turns(cells) == 2 * (lanes - 1)
    assert cells[-1] == exit_cell(entry, rect, axis)


def test_sweep_runs_along_the_longer_side():
    lab = np.zeros((4, 10), dtype=np.int32)
    lab[:, 6:] = 1
    lab[:, 8:] = -1
    assert list(sweep_axes(lab, 2)) == [0, 1]  # 4×6: along rows; 4×2: along columns


# ---- dead-zone escape (eqs. 6–9, Table 1) --------------------------------------------------


def _fig11():
    """Fig. 11 as read from Table 1: the robot swept the lanes x ≤ 3 of its
    sub-region (visited once), an obstacle fills x 4..7, y 7..10 (the map's
    top row is y = 10), and it stands in the dead zone at (3D, 10D).
    Arrays are indexed [y, x]."""
    blocked = np.zeros((11, 10), dtype=bool)
    blocked[7:11, 4:8] = True
    visits = np.zeros(blocked.shape, dtype=np.int32)
    visits[:, :4] = 1
    visits[10, 3] = 2  # standing there: counted once more
    return blocked, visits


TABLE1 = {  # (x, y) of the robot -> f_i by (dx, dy); None = outside the map
    (3, 10): {
        (0, -1): 0.485,
        (-1, 0): -0.12,
        (-1, -1): 0.255,
        (1, 0): -math.inf,
        (1, -1): -math.inf,
    },
    (3, 9): {(0, 1): -1.475, (0, -1): 0.475, (-1, 1): -0.445, (-1, 0): -0.16, (-1, -1): 0.225},
    (3, 8): {(0, 1): -1.445, (0, -1): 0.445, (-1, 1): -0.475, (-1, 0): -0.225, (-1, -1): 0.16},
    (3, 7): {(0, 1): -1.355, (0, -1): 0.355, (-1, 0): -0.355, (-1, -1): 0.0, (1, 0): -math.inf},
}


def test_table1_path_selection_values_and_escape_path():
    blocked, visits = _fig11()
    path = escape(blocked, visits.copy(), (10, 3), t=0.5, corner_cutting=True)
    assert path == [(9, 3), (8, 3), (7, 3), (6, 4)]  # Table 1's last row, as (y, x)
    v = visits.copy()
    for x, y in [(3, 10), (3, 9), (3, 8), (3, 7)]:
        f = selection_values(blocked, v, (y, x), (6, 4), t=0.5)
        assert (0, 1) not in f or (x, y) != (3, 10)  # above the top row: '-'
        for key, want in TABLE1[(x, y)].items():
            if math.isinf(want):
                assert f[key] == want
            else:
                assert f[key] == pytest.approx(want, abs=0.006), ((x, y), key)
        best = max((k for k in f), key=lambda k: f[k])
        y, x = y + best[1], x + best[0]
        v[y, x] += 1
    # Two entries of Table 1's (3D, 7D) column do not follow eqs. 4 and 8:
    # it prints 2 for (x+D, y−D) and −1 for (x−D, y+D); with x_i = 1 and 0
    # and cos 0 = 1, cos π = −1 the formula gives 1.5 and −0.5.
    f = selection_values(blocked, _after_three_steps(), (7, 3), (6, 4), 0.5)
    assert f[(1, -1)] == pytest.approx(1.5) and f[(-1, 1)] == pytest.approx(-0.5)


def _after_three_steps():
    blocked, visits = _fig11()
    for y in (9, 8, 7):
        visits[y, 3] += 1
    return visits


def test_escape_without_corner_cutting_goes_round():
    blocked, visits = _fig11()
    path = escape(blocked, visits, (10, 3), t=0.5, corner_cutting=False)
    assert path is not None and visits[path[-1]] == 1
    for (r0, c0), (r1, c1) in zip([(10, 3), *path], path, strict=False):
        dr, dc = r1 - r0, c1 - c0
        assert not (dr and dc and (blocked[r0 + dr, c0] or blocked[r0, c0 + dc]))


def test_escape_rejects_t_outside_0_1():
    blocked, visits = _fig11()
    with pytest.raises(ValueError):
        selection_values(blocked, visits, (10, 3), (6, 4), t=1.5)


# ---- switching (§4, eqs. 10–11) ------------------------------------------------------------


def test_associated_cells_are_the_corners_counter_clockwise():
    lab = np.full((8, 8), -1, dtype=np.int32)
    lab[2:5, 1:7] = 3
    assert associated_cells(lab, 3) == [(2, 1), (2, 6), (4, 6), (4, 1)]


def test_exit_parity():
    rect = (0, 3, 0, 5)  # 4 rows, 6 columns
    assert exit_cell((0, 0), rect, 1) == (0, 5)  # 6 lanes, 5 turns (odd): same side
    assert exit_cell((0, 0), rect, 0) == (3, 0)  # 4 row lanes, 3 turns (odd): entry's column
    assert exit_cell((0, 0), (0, 2, 0, 5), 0) == (2, 5)  # 3 lanes, 2 turns (even): opposite
    assert exit_cell((3, 5), rect, 1) == (3, 0)


def test_nearest_entry_eq11():
    assert nearest_entry((5, 5), [(0, 0), (6, 7), (5, 9)]) == (6, 7)


def test_switch_goes_straight_when_free_and_round_an_obstacle_otherwise():
    blocked = np.zeros((10, 10), dtype=bool)
    visits = np.zeros((10, 10), dtype=np.int32)
    line = switch_path(blocked, visits, (0, 0), (0, 6))
    assert line == [(0, c) for c in range(1, 7)]
    blocked[0:3, 3] = True
    visits[:] = 0
    path = switch_path(blocked, visits, (0, 0), (0, 6))
    assert path is not None and path[-1] == (0, 6)
    assert not any(blocked[p] for p in path)
