import math

import numpy as np
import pytest

from sim_robot.lidar import Lidar
from sim_robot.world import World


@pytest.fixture(scope="module")
def world():
    return World(seed=1)


def test_occupancy_grid(world):
    grid, res, origin = world.occupancy_grid()
    assert grid.dtype == bool and grid.shape == (600, 800)
    assert res == pytest.approx(0.1) and origin == (0.0, 0.0)
    c, r = world.to_cell(19.0, 36.0)  # centre of tank T-101
    assert grid[r, c]
    c, r = world.to_cell(66.0, 45.0)  # the dock is free
    assert not grid[r, c]


def test_robot_cannot_drive_through_a_tank(world):
    # inside the bund, west of tank T-102 (centre 41, 36, r 5), driving east at it
    world.set_pose(33.0, 36.0, 0.0)
    for _ in range(400):
        world.move_robot(1.0, 0.0, 0.05, 0.35)
    p = world.pose
    assert p.x == pytest.approx(41.0 - 5.0 - 0.35, abs=0.15)
    assert world.clearance(p.x, p.y) >= 0.35
    assert world.move_robot(1.0, 0.0, 0.05, 0.35)  # still blocked


def test_robot_heading_west_keeps_moving_when_its_heading_wraps():
    w = World(seed=1)
    w.walkers, w.vehicles = [], []
    x0, y0 = w.dock[0] - 1.0, w.dock[1]
    w.set_pose(x0, y0, math.pi - 0.002)  # turning left through ±π
    w.move_robot(0.6, 0.05, 0.1, 0.3)
    p = w.pose
    assert p.theta < 0  # wrapped
    assert p.x == pytest.approx(x0 - 0.06, abs=1e-3) and abs(p.y - y0) < 1e-3


def test_robot_slides_along_a_wall(world):
    world.set_pose(66.0, 47.0, math.radians(60))  # towards the control room's south wall
    for _ in range(200):
        world.move_robot(0.5, 0.0, 0.05, 0.35)
    p = world.pose
    assert p.y < 49.0 - 0.3 and p.x > 67.0


def test_lidar_range_to_a_known_wall(world):
    lidar = Lidar(world, np.random.default_rng(0), noise_m=0.0, dropout=0.0)
    # facing north towards the control room wall at y = 49.0 from y = 46.0
    s = lidar.scan(66.0, 46.0, math.pi / 2)
    assert len(s.ranges_m) == 360
    i0 = int(round((0.0 - s.angle_min_rad) / s.angle_increment_rad))
    assert s.ranges_m[i0] == pytest.approx(3.0, abs=0.08)
    i_back = int(round((math.pi / 2 - s.angle_min_rad) / s.angle_increment_rad))  # west
    assert s.ranges_m[i_back] > 5.0


def test_lidar_ranges_end_at_the_cell_face_not_a_march_step_behind(world):
    lidar = Lidar(world, np.random.default_rng(0), noise_m=0.0, dropout=0.0)
    # the control room wall's south face is at y = 49.0; step the robot in 1 cm
    # steps: a coarse 5 cm march would be up to 5 cm long, biased by ~2.5 cm
    i0 = int(round((0.0 + math.pi) / (2 * math.pi / 360)))
    err = [lidar.scan(66.0, 46.0 + k * 0.01, math.pi / 2).ranges_m[i0] - (3.0 - k * 0.01)
           for k in range(10)]
    assert np.max(np.abs(err)) <= 0.0051
    assert abs(np.mean(err)) < 0.004


def test_gas_plume_is_strongest_at_the_source(world):
    src = world.gas_sources[0]
    at = world.gas_lel_pct(src["x"], src["y"], 0.0)
    far = world.gas_lel_pct(src["x"] + 30, src["y"] + 20, 0.0)
    assert at > 10.0 and far < at / 5
    wd, _ = world.wind_at(0.0)
    down = world.gas_lel_pct(src["x"] + 6 * math.cos(wd), src["y"] + 6 * math.sin(wd), 0.0)
    up = world.gas_lel_pct(src["x"] - 6 * math.cos(wd), src["y"] - 6 * math.sin(wd), 0.0)
    assert down > 3 * up


def test_climate_follows_the_day(world):
    t15 = (15.0 - 9.0) * 3600  # sim starts at 09:00
    t03 = (27.0 - 9.0) * 3600
    assert world.ambient(t15)[0] > world.ambient(t03)[0] + 10
    assert world.ambient(t15)[1] < world.ambient(t03)[1]


def test_committed_ros_map_matches_the_layout(world, tmp_path):
    """app/resources/station/station_map.yaml is regenerated with `python -m sim_robot.world`."""
    import cv2

    from sim_robot.config import DEFAULT_STATION

    committed = cv2.imread(str(DEFAULT_STATION.with_name("station_map.png")),
                           cv2.IMREAD_GRAYSCALE)
    world.export_ros_map(tmp_path / "m.yaml")
    fresh = cv2.imread(str(tmp_path / "m.png"), cv2.IMREAD_GRAYSCALE)
    assert committed is not None and np.array_equal(committed, fresh)
    assert np.array_equal(np.flipud(fresh == 0), world.occupancy_grid()[0])


def test_people_walk_and_are_seen_and_solid():
    w = World(seed=1)
    walker = w.walkers[0]
    t = 0.0
    w.clock = lambda: t
    x0, y0 = walker.position(0.0)
    moved = max(math.hypot(walker.position(s)[0] - x0, walker.position(s)[1] - y0)
                for s in range(0, 200, 5))
    assert moved > 5.0  # they walk
    # stand 3 m from a person (a fixed instant) and look at them with the lidar
    px, py = walker.position(t)
    w.set_pose(px - 3.0, py, 0.0)
    lidar = Lidar(w, np.random.default_rng(0), noise_m=0.0, dropout=0.0)
    s = lidar.scan(px - 3.0, py, 0.0)
    i0 = int(round((0.0 - s.angle_min_rad) / s.angle_increment_rad))
    assert s.ranges_m[i0] == pytest.approx(3.0 - walker.radius, abs=0.02)
    # and the robot cannot drive through them
    for _ in range(100):
        w.move_robot(0.5, 0.0, 0.05, 0.35)
    assert w.pose.x == pytest.approx(px - walker.radius - 0.35, abs=0.06)


def test_start_in_front_of_a_gauge_looking_at_it():
    w = World(seed=0)
    g = w.gauges[0]
    x, y, th = w.pose_facing_gauge(g.id, standoff_m=1.5)
    assert math.hypot(x - g.x, y - g.y) == pytest.approx(1.5)
    # the robot's heading points from it to the gauge
    assert math.cos(th - math.atan2(g.y - y, g.x - x)) == pytest.approx(1.0)
    with pytest.raises(ValueError, match="no gauge 'XX-1'"):
        w.pose_facing_gauge("XX-1")
