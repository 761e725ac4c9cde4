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


def _cell(g, x, y):
    c = np.floor((np.array([x, y]) - g.origin_xy) / g.resolution_m).astype(int)
    return g.cells[c[1], c[0]]


def _scan_of(walls_m, n=360):
    """A full-turn scan from the origin: ``walls_m(angles)`` gives each beam's
    range (inf: no return); returns the points and the no-return rays."""
    from app.core.localisation.free_space import no_return_rays

    a = -np.pi + 2 * np.pi / n * np.arange(n)
    r = walls_m(a)
    ok = np.isfinite(r)
    pts = np.column_stack((r[ok] * np.cos(a[ok]), r[ok] * np.sin(a[ok])))
    return pts, no_return_rays(r, a, max_range_m=11.9)


def test_a_cart_seen_against_open_ground_is_cleared_once_later_beams_see_through_it():
    """Something standing 8 m away with open ground behind it (no return)
    for a few scans, then gone: with the no-return beams as free space its
    cells are free; from the returns alone nothing ever crossed them again."""
    north = lambda a: np.where(np.abs(a - np.pi / 2) < 0.8, 3.0, np.inf)  # noqa: E731

    def with_cart(a):
        return np.where(np.abs(a) < 0.06, 8.0, north(a))  # ~1 m wide, straight ahead

    seen = [_scan_of(with_cart) for _ in range(4)]
    gone = [_scan_of(north) for _ in range(8)]
    poses = np.zeros((12, 3))
    pts = [s[0] for s in seen + gone]
    free = [s[1] for s in seen + gone]
    g = build_grid(poses, pts, 0.1, free_scans=free)
    where = [(x, y) for x in (7.95, 8.05) for y in np.arange(-0.45, 0.5, 0.1)]
    assert not any(_cell(g, x, y) == OCCUPIED for x, y in where)
    assert _cell(g, 8.05, 0.15) == FREE
    assert all(_cell(g, x, y) == OCCUPIED for x, y in gone[0][0])  # the wall that stayed stays
    along = lambda deg, d: (d * np.cos(np.radians(deg)), d * np.sin(np.radians(deg)))  # noqa: E731
    assert _cell(g, *along(5, 11.0)) == FREE  # open ground, seen as such
    assert _cell(g, *along(90, 5.0)) == UNKNOWN  # behind the wall: never seen
    assert _cell(g, *along(175, 11.0)) == FREE and _cell(g, *along(175, 12.4)) == UNKNOWN
    old = build_grid(poses, pts, 0.1)  # the returns alone keep the cart
    assert sum(_cell(old, x, y) == OCCUPIED for x, y in where) >= 7


def test_a_wall_seen_in_one_scan_stays_and_dropouts_in_a_wall_do_not_clear_it():
    rng = np.random.default_rng(4)

    def post(a):  # a post 6 m off, seen by a handful of beams, open ground round it
        return np.where(np.abs(a - 1.0) < 0.03, 6.0, np.inf)

    def room(a):  # a wall 2.5 m off all round, a few beams lost to dropouts
        r = np.full(a.shape, 2.5)
        r[rng.random(a.shape) < 0.05] = np.inf
        return r

    once = _scan_of(post)
    g = build_grid(np.zeros((1, 3)), [once[0]], 0.1, free_scans=[once[1]])
    assert _cell(g, 6 * np.cos(1.0), 6 * np.sin(1.0)) == OCCUPIED
    scans = [_scan_of(room) for _ in range(6)]
    g = build_grid(np.zeros((6, 3)), [s[0] for s in scans], 0.1, free_scans=[s[1] for s in scans])
    ring = [_cell(g, 2.5 * np.cos(t), 2.5 * np.sin(t)) for t in np.linspace(-3, 3, 120)]
    assert all(c == OCCUPIED for c in ring)
    assert _cell(g, 3.5, 0.05) == UNKNOWN  # a dropout's ray stops short of the wall


def test_the_grid_cells_stay_put_as_the_map_grows():
    """The cells' corners lie on multiples of the resolution, whatever the
    map's extent: a growing map redrawn keeps each wall in its cells."""
    wall = np.column_stack((np.full(41, 2.03), np.linspace(-1, 1, 41)))
    small = build_grid(np.array([[0.0, 0.0, 0.0]]), [wall], 0.1)
    bigger = build_grid(np.array([[0.0, 0.0, 0.0], [-3.37, 0.0, 0.0]]), [wall, wall], 0.1)
    for g in (small, bigger):
        assert np.allclose(np.round(np.array(g.origin_xy) / 0.1), np.array(g.origin_xy) / 0.1)
        assert _cell(g, 2.05, 0.05) == OCCUPIED


def _drive_past_wall(wall_y_m, steps=20, n=360, seed=0):
    """Scans (1.5 cm range noise, no-return rays) from 1 m of path along x,
    a scan per 0.05 m, with a long wall at y = ``wall_y_m`` beside it."""
    from app.core.localisation.free_space import no_return_rays

    rng = np.random.default_rng(seed)
    a = -np.pi + 2 * np.pi / n * np.arange(n)
    poses, pts, free = [], [], []
    for k in range(steps):
        with np.errstate(divide="ignore"):
            r = np.where(np.sin(a) > 1e-9, wall_y_m / np.sin(a), np.inf)
        r[r > 11.9] = np.inf
        r = r + np.where(np.isfinite(r), 0.015 * rng.standard_normal(n), 0.0)
        ok = np.isfinite(r)
        poses.append((0.05 * k, 0.0, 0.0))
        pts.append(np.column_stack((r[ok] * np.cos(a[ok]), r[ok] * np.sin(a[ok]))))
        free.append(no_return_rays(r, a, 11.9))
    return np.array(poses), pts, free


def _wall_kept(g, wall_y_m):
    """Share of the wall's 0.1 m stretches 2-10 m ahead whose face cell is occupied."""
    row = int(np.floor((wall_y_m - g.origin_xy[1]) / g.resolution_m))
    cols = np.floor((np.arange(2.05, 10.0, 0.1) - g.origin_xy[0]) / g.resolution_m)
    return float((g.cells[row, cols.astype(int)] == OCCUPIED).mean())


def test_a_wall_whose_face_lies_inside_its_cells_is_not_worn_away_by_grazing_beams():
    """The wall's face at y = 1.05 m, in the middle of its 0.1 m cells (a
    real map's walls fall anywhere in its cells): the beams that end farther
    along it run through the near half of its face cells on their last
    decimetres. Stopped one cell short along the ray (the old rule) they wore
    away over a third of the face at the mapping mode's 25 % (l_free −0.3);
    stopped one cell off the surface they ended on, the face stays."""
    poses, pts, free = _drive_past_wall(1.05)
    old = build_grid(poses, pts, 0.1, l_free=-0.3, free_scans=free)
    new = build_grid(poses, pts, 0.1, l_free=-0.3, free_scans=free, stop_at_surface=True)
    assert _wall_kept(old, 1.05) < 0.75
    assert _wall_kept(new, 1.05) > 0.9
    assert _cell(new, 5.0, 0.85) == FREE  # two cells off the wall: still cleared
    assert _cell(new, 5.0, 0.5) == FREE


def test_a_wall_seen_head_on_is_cleared_up_to_one_cell_short_as_before():
    """At normal incidence the surface rule is the old one: the free ray
    stops one cell short of the return, so the cell in front of the wall's
    is free and the rest of the grid is the same."""
    angles = np.linspace(-0.3, 0.3, 61)
    pts = np.column_stack((np.full(61, 2.05), 2.05 * np.tan(angles)))  # a wall at x = 2.05 m
    pose = np.array([[0.0, 0.0, 0.0]])
    old = build_grid(pose, [pts], 0.1)
    new = build_grid(pose, [pts], 0.1, stop_at_surface=True)
    assert _cell(new, 2.05, 0.0) == OCCUPIED and _cell(new, 1.85, 0.0) == FREE
    assert np.array_equal(old.cells, new.cells)
