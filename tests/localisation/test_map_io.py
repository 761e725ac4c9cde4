import numpy as np

from app.core.localisation.map_io import (
    FREE,
    OCCUPIED,
    UNKNOWN,
    OccupancyGrid,
    build_grid,
    load_map,
    save_map,
)
from app.core.planner import GridMap, load_ros_map, save_ros_map


def test_map_round_trip_keeps_unknown_cells(tmp_path):
    cells = np.full((6, 8), UNKNOWN, np.int8)
    cells[1:5, 1:7] = FREE
    cells[1, 1:7] = OCCUPIED
    cells[3, 4] = UNKNOWN
    grid = OccupancyGrid(cells, 0.05, (-1.5, 2.25))
    save_map(grid, tmp_path / "m.yaml")
    back = load_map(tmp_path / "m.yaml")
    assert np.array_equal(back.cells, cells)
    assert back.resolution_m == 0.05 and back.origin_xy == (-1.5, 2.25)
    assert "mode: trinary" in (tmp_path / "m.yaml").read_text()


def test_planner_writer_keeps_unknown_cells_too(tmp_path):
    cells = np.full((4, 5), FREE, np.int8)
    cells[0, 0] = OCCUPIED
    cells[3, 4] = UNKNOWN
    save_map(OccupancyGrid(cells, 0.5, (0.0, 0.0)), tmp_path / "a.yaml")
    g = load_ros_map(tmp_path / "a.yaml")  # unknown is blocked for planning...
    assert g.blocked[3, 4] and g.unknown[3, 4]
    save_ros_map(g, tmp_path / "b.yaml")  # ...and is written back as unknown
    assert np.array_equal(load_map(tmp_path / "b.yaml").cells, cells)
    save_ros_map(GridMap(cells == OCCUPIED, 0.5), tmp_path / "c.yaml")  # no mask: two states
    assert not (load_map(tmp_path / "c.yaml").cells == UNKNOWN).any()


def test_grid_from_a_scan_marks_the_wall_the_free_ray_and_leaves_the_rest_unknown():
    angles = np.linspace(-0.3, 0.3, 61)
    pts = np.column_stack((np.full(61, 2.0), 2.0 * np.tan(angles)))  # a wall at x = 2 m
    g = build_grid(np.array([[0.0, 0.0, 0.0]]), [pts], resolution_m=0.1)

    def cell(x, y):
        c = np.floor((np.array([x, y]) - g.origin_xy) / g.resolution_m).astype(int)
        return g.cells[c[1], c[0]]

    assert cell(2.0, 0.0) == OCCUPIED
    assert cell(1.0, 0.0) == FREE
    assert cell(-0.8, 0.0) == UNKNOWN  # behind the sensor: never seen
    assert cell(2.6, 0.0) == UNKNOWN  # behind the wall
