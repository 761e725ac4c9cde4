import numpy as np
import pytest

from app.core.planner import GridMap, load_movingai_map, load_movingai_scen, load_ros_map
from app.core.planner.grid import parse_movingai_map, save_ros_map


def test_world_cell_round_trip():
    g = GridMap(np.zeros((40, 60), bool), 0.05, (-1.0, 2.0))
    r, c = g.world_to_cell(0.0, 2.5)
    assert (r, c) == (10, 20)
    x, y = g.cell_to_world(r, c)
    assert (x, y) == pytest.approx((0.025, 2.525))
    assert g.world_to_cell(x, y) == (r, c)
    assert not g.in_bounds(*g.world_to_cell(-1.01, 2.0))


def test_inflation_blocks_within_radius():
    b = np.zeros((41, 41), bool)
    b[20, 20] = True
    g = GridMap(b, 0.1).inflate(0.3)
    assert g.blocked[20, 23] and g.blocked[23, 20]
    assert not g.blocked[20, 25] and not g.blocked[24, 24]
    assert g.blocked.sum() > 20
    # The clearance field: distance to the obstacle's surface.
    d = GridMap(b, 0.1).distance_m
    assert d[20, 20] == 0.0
    assert d[20, 25] == pytest.approx(0.45, abs=1e-6)


def test_ros_map_round_trip_and_thresholds(tmp_path):
    img = np.full((4, 5), 254, np.uint8)
    img[0, 0] = 0  # occupied, top-left of the image = highest y
    img[3, 4] = 205  # unknown (p ≈ 0.2)
    import cv2

    cv2.imwrite(str(tmp_path / "m.pgm"), img)
    (tmp_path / "m.yaml").write_text(
        "image: m.pgm  # the picture\nresolution: 0.5\norigin: [-1.0, -2.0, 0.0]\n"
        "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    g = load_ros_map(tmp_path / "m.yaml")
    assert g.shape == (4, 5) and g.resolution_m == 0.5 and g.origin_xy == (-1.0, -2.0)
    assert g.blocked[3, 0]  # flipped: image row 0 is the top (row 3 here)
    assert g.blocked[0, 4]  # unknown counts as blocked by default
    assert g.blocked.sum() == 2
    assert not load_ros_map(tmp_path / "m.yaml", unknown_blocked=False).blocked[0, 4]
    save_ros_map(g, tmp_path / "copy.yaml")
    g2 = load_ros_map(tmp_path / "copy.yaml")
    assert np.array_equal(g2.blocked, g.blocked) and g2.origin_xy == g.origin_xy


def test_ros_map_missing_key(tmp_path):
    (tmp_path / "bad.yaml").write_text("resolution: 0.1\n")
    with pytest.raises(ValueError, match="image"):
        load_ros_map(tmp_path / "bad.yaml")


def test_movingai_map_and_scen(tmp_path):
    text = "type octile\nheight 3\nwidth 4\nmap\n..@.\nT...\n.GS@\n"
    b = parse_movingai_map(text)
    assert b.tolist() == [
        [False, False, True, False],
        [True, False, False, False],
        [False, False, False, True],
    ]
    (tmp_path / "a.map").write_text(text)
    assert load_movingai_map(tmp_path / "a.map").shape == (3, 4)
    (tmp_path / "a.scen").write_text("version 1\n0\tmaps/a.map\t4\t3\t0\t0\t3\t1\t3.41421\n\n")
    (q,) = load_movingai_scen(tmp_path / "a.scen")
    assert q.start == (0, 0) and q.goal == (1, 3) and q.optimal_length == pytest.approx(3.41421)
    with pytest.raises(ValueError):
        parse_movingai_map("type octile\nmap\n..\n")
