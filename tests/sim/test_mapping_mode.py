"""Mapping mode: the robot driven by hand builds a map from its own scans."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from app.comm import protocol as P
from app.core.localisation.map_io import load_map
from app.core.localisation.se2 import compose
from sim_robot.config import SimConfig
from sim_robot.mapping_mode import MappingMode
from sim_robot.mcu_link import MotorCmd
from sim_robot.patrol_sim import OfflinePatrol


def _drive(op, v, w, seconds):
    op._send(MotorCmd(v, w))
    end = op.t + seconds
    while op.t < end:
        op.step()  # the executor owns nothing: keep-alives hold the command
        op.nav.perceive(op.t)


def test_driving_by_hand_builds_a_map_that_matches_the_station(tmp_path):
    op = OfflinePatrol(SimConfig(seed=2, video=False))
    op.world.walkers, op.world.vehicles = [], []
    op.nav.mapping = m = MappingMode(tmp_path)
    m.start()
    _drive(op, 0.5, 0.0, 12.0)  # west along the road from the dock
    _drive(op, 0.0, 0.6, 5.2)  # turn round
    _drive(op, 0.5, 0.0, 8.0)
    assert m.scans > 40 and op.world.collisions == []
    g = m.grid()
    occ = np.argwhere(g.occupied)
    mapped = np.column_stack((g.origin_xy[0] + (occ[:, 1] + 0.5) * g.resolution_m,
                              g.origin_xy[1] + (occ[:, 0] + 0.5) * g.resolution_m))
    true_occ = np.argwhere(op.world.occupied)
    walls = (true_occ[:, ::-1] + 0.5) * op.world.res
    d, _ = cKDTree(walls).query(mapped)
    assert len(mapped) > 200
    # the mapped walls lie on the station's walls: near ones within a cell or
    # so, walls 10-12 m off within 0.35 m (a 1° heading error there is 0.2 m)
    assert np.median(d) <= 0.1
    assert np.mean(d <= 0.35) >= 0.97
    assert g.unknown.any()  # what it never saw stays unknown
    img = m.map_image()
    assert (img.width, img.height) == (g.cells.shape[1], g.cells.shape[0])
    path = m.save("road-east", g)
    back = load_map(path)
    assert np.array_equal(back.cells, g.cells)  # unknown cells kept unknown
    # save() without a grid writes the finished map (final solve on a copy),
    # and the live mapper the robot keeps mapping with is left as it was
    live = [p.copy() for p in m.mapper.poses]
    finished = m.snapshot().finish()
    assert all(np.array_equal(a, b) for a, b in zip(live, m.mapper.poses, strict=True))
    assert np.array_equal(load_map(m.save("road-east-final")).cells, finished.cells)
    try:
        m.save("../escape")
    except ValueError as e:
        assert "letters" in str(e)
    else:
        raise AssertionError("a path in the map name was accepted")
    m.stop()
    assert not m.active


def test_relay_mapping_commands_publish_the_growing_map_and_save_it(tmp_path, monkeypatch):
    import threading

    from sim_robot.mapping_mode import MapSnapshot, MapView
    from sim_robot.sim import SimRobot

    # the final solve is held until the robot has answered other commands:
    # save_map must not run it with the relay's lock held
    release, finishing = threading.Event(), []
    real_finish = MapSnapshot.finish

    def held_finish(snap):
        finishing.append(threading.current_thread().name)
        assert release.wait(120)
        return real_finish(snap)

    monkeypatch.setattr(MapSnapshot, "finish", held_finish)
    # the first drawing of the growing map is held too: the navigation must
    # step on meanwhile (it was drawn on the navigation thread with the lock held)
    draw_go, drawing = threading.Event(), []
    real_image = MapView.image

    def held_image(view):
        drawing.append(threading.current_thread().name)
        if len(drawing) == 1:
            assert draw_go.wait(120)
        return real_image(view)

    monkeypatch.setattr(MapView, "image", held_image)

    from .conftest import Desk, wait_until

    r = SimRobot(SimConfig(video=False, seed=2, time_scale=5.0, maps_dir=str(tmp_path)))
    r.world.walkers, r.world.vehicles = [], []
    r.start()
    desk = Desk(*r.address)
    try:
        assert r.relay.nav_ready.wait(30)

        def cmd(command, **args):
            seq = desk.send(P.Command(command, args))
            return wait_until(lambda: desk.ack(seq), 30)

        station = wait_until(lambda: desk.of(P.MsgType.MAP), 30)[0]  # sent on connecting
        assert cmd("start_mapping").ok
        assert not cmd("save_map", name="x y").ok
        # the operator drives as a desk does: the drive command renewed well
        # within the relay's deadman (0.5 s) until the growing map has come
        driven = threading.Event()

        def keep_driving():
            while not driven.wait(0.1):
                desk.send(P.Command("drive", {"linear_mps": 0.4, "angular_rps": 0.0}))

        driver = threading.Thread(target=keep_driving, daemon=True)
        driver.start()
        try:
            # the first drawing once the mapper has its first scan; deadlines
            # for a starved host: the wait is on the robot's own progress
            wait_until(lambda: drawing, 60, what=lambda: f"a drawing ({r.relay.counters})")
            steps = r.relay.counters["nav_steps"]
            wait_until(lambda: r.relay.counters["nav_steps"] > steps + 10, 30,
                       what="navigation steps while the map is drawn")
            assert drawing == ["relay-map"]
            draw_go.set()
            # the growing map (smaller than the station's, from what the robot saw)
            grown = wait_until(lambda: [m for m in desk.of(P.MsgType.MAP)
                                        if m.width < station.width], 60,
                               what=lambda: f"the growing map ({r.relay.counters})")
        finally:
            driven.set()
            driver.join()
        assert grown[-1].height < station.height
        assert cmd("save_map", name="test-map").ok
        assert wait_until(lambda: desk.events("map_saving"), 30)
        wait_until(lambda: finishing, 30)
        assert not cmd("save_map", name="again").ok  # one save at a time
        # the robot still answers while the map is being finished
        assert cmd("drive", linear_mps=0.0, angular_rps=0.0).ok
        assert finishing == ["map-save"] and not desk.events("map_saved")
        release.set()
        assert wait_until(lambda: desk.events("map_saved"), 60)
        assert (tmp_path / "test-map.yaml").exists()
        assert cmd("stop_mapping").ok
        assert not cmd("stop_mapping").ok
    finally:
        desk.close()
        r.close()


def test_the_mappers_kernels_are_run_before_the_robot_serves():
    """The relay runs the mapper's compiled kernels in its warm-up (before the
    desk server and the MCU link start): on a first run they compile, tens of
    seconds of CPU, which the first scans after start_mapping spent on the
    navigation thread with the relay's lock held (no step, no keep-alive: the
    MCU's link watchdog stopped the robot). A process of its own, so that no
    other test has compiled them first."""
    import subprocess
    import sys

    code = """
import numba.core.registry as reg
from app.core.localisation import map_io, match_covariance, submap_match
from sim_robot.config import SimConfig
from sim_robot.sim import SimRobot
kernels = [map_io._accumulate, submap_match._refine_distance, submap_match._values_kernel,
           match_covariance._olson_cov, submap_match._grid_search_cells]
assert all(isinstance(k, reg.CPUDispatcher) for k in kernels)
r = SimRobot(SimConfig(video=False, seed=2))
r.relay.prepare()
print(sorted(k.__name__ for k in kernels if not k.signatures))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=900, check=True).stdout
    assert out.strip().splitlines()[-1] == "[]", out


def test_points_on_a_tracked_person_stay_out_of_the_map():
    """A person the tracker follows is matched against no wall (localisation)
    and is drawn into no map: the mapper gets the scan without them."""
    import math

    from sim_robot.lidar import Lidar
    from sim_robot.localisation import RobotLocaliser, load_station_map
    from sim_robot.world import World

    w = World(seed=1)
    w.walkers, w.vehicles = [], []
    lidar = Lidar(w, np.random.default_rng(3))
    start = (62.9, 45.0, math.pi)
    loc = RobotLocaliser(load_station_map(), start)
    loc.predict(start)
    scan = lidar.scan(*start)
    loc.correct(scan)
    pts = loc.last_points
    ahead = pts[np.argmin(np.abs(np.arctan2(pts[:, 1], pts[:, 0])))]  # the beam straight ahead
    c, s = math.cos(start[2]), math.sin(start[2])
    wx, wy = start[0] + c * ahead[0] - s * ahead[1], start[1] + s * ahead[0] + c * ahead[1]
    mover = np.array([[wx, wy, 0.0, 0.0, 0.3]])  # a tracked "person" where that beam ends
    loc.predict((start[0] - 0.1, start[1], start[2]))  # moved: the scan is fused
    loc.correct(scan, mover)
    near = np.hypot(loc.static_points[:, 0] - ahead[0], loc.static_points[:, 1] - ahead[1])
    assert (near > 0.3).all() and len(loc.static_points) < len(loc.last_points)
    assert np.hypot(loc.last_points[:, 0] - ahead[0], loc.last_points[:, 1] - ahead[1]).min() < 0.05


def test_mapping_mode_maps_a_scan_per_quarter_metre_or_ten_degrees(tmp_path):
    """At 5 Hz the station lidar sees the world every 0.1 m; the mapper gets a
    scan per 0.25 m of path or 10° of turn, as far apart as the logs it was made on."""
    m = MappingMode(tmp_path)
    m.start()
    ang = np.linspace(-np.pi, np.pi, 360, endpoint=False)
    room = np.column_stack((4 * np.cos(ang), 3 * np.sin(ang)))  # an oval room
    for k in range(30):  # 0.1 m per scan: 3 m
        m.add((0.1 * k, 0.0, 0.0), room)
    assert m.scans == 10  # 0, 0.3, 0.6, ... (0.25 m apart at least)
    for k in range(1, 19):  # turning on the spot, 3° per scan: 54°
        m.add((2.9, 0.0, np.radians(3 * k)), room)
    assert m.scans == 10 + 4  # at 12°, 24°, 36° and 48° (the position moved 0.2 m only)
    assert len(m.mapper.poses) == m.scans


def test_the_map_is_drawn_from_every_moving_scan_and_follows_the_solved_nodes(tmp_path):
    """Scans between the mapper's nodes are kept (relative to the latest node)
    and drawn into the map; when a node's pose is solved again, its scans
    move with it."""
    m = MappingMode(tmp_path)
    m.start()
    ang = np.linspace(-np.pi, np.pi, 360, endpoint=False)
    room = np.column_stack((4 * np.cos(ang), 3 * np.sin(ang)))
    for k in range(30):  # 0.1 m per scan: 3 m
        m.add((0.1 * k, 0.0, 0.0), room)
    for _ in range(5):  # standing still: nothing new to keep
        m.add((2.9, 0.0, 0.0), room)
    assert m.scans == 10 and len(m.kept) == 30
    v = m.view()
    assert len(v.poses) == 30
    # a scan kept between nodes sits at its node's pose plus the odometry since
    k = next(i for i, s in enumerate(m.kept) if s.rel.any())
    node = m.kept[k].node
    assert np.allclose(v.poses[k], compose(m.anchor, compose(m.mapper.poses[node],
                                                             m.kept[k].rel)))
    m.mapper.poses[node] = m.mapper.poses[node] + np.array([0.0, 0.5, 0.0])  # solved again
    moved = m.view().poses
    assert np.allclose(moved[k] - v.poses[k], [0.0, 0.5, 0.0], atol=1e-9)
    others = [i for i, s in enumerate(m.kept) if s.node != node]
    assert np.allclose(moved[others], v.poses[others])


def test_the_kept_scans_stay_bounded(tmp_path, monkeypatch):
    import sim_robot.mapping_mode as mm

    monkeypatch.setattr(mm, "MAX_KEPT", 90)
    m = MappingMode(tmp_path)
    m.start()
    ang = np.linspace(-np.pi, np.pi, 360, endpoint=False)
    room = np.column_stack((4 * np.cos(ang), 3 * np.sin(ang)))
    for k in range(200):  # 0.1 m per scan: 20 m in a long oval "corridor"
        m.add((0.1 * k, 0.0, 0.0), room)
    assert len(m.kept) <= 90 and m.scans > 60
    nodes = {s.node for s in m.kept if not s.rel.any()}
    assert len(nodes) == m.scans  # every node's own scan is kept


def test_lone_returns_are_drawn_into_the_map_but_not_matched_and_movers_stay_out():
    """A far wall at a grazing angle comes back as lone returns between range
    jumps: matching drops them, the map keeps them (RobotLocaliser.map_points);
    points on a tracked obstacle stay out of both."""
    import math

    from sim_robot.localisation import RobotLocaliser, load_station_map

    start = (62.9, 45.0, math.pi)
    loc = RobotLocaliser(load_station_map(), start)
    loc.predict(start)
    n = 360
    ranges = np.full(n, 3.0, np.float32)  # a near wall all round...
    ranges[100:140] = np.where(np.arange(40) % 2, 6.0, 9.0)  # ...and lone far returns
    scan = P.LidarScan(0, -math.pi, 2 * math.pi / n, 12.0, ranges)
    ahead = (start[0] - 3.0, start[1])  # where the beam straight ahead ends
    mover = np.array([[ahead[0], ahead[1], 0.0, 0.0, 0.3]])
    loc.predict((start[0] - 0.1, start[1], start[2]))  # moved: the scan is fused
    loc.correct(scan, mover)
    drawn = loc.map_points()
    lone = np.hypot(drawn[:, 0], drawn[:, 1]) > 5.0
    assert lone.sum() == 40  # every lone return is drawn...
    matched = loc.static_points
    assert (np.hypot(matched[:, 0], matched[:, 1]) < 5.0).all()  # ...none matched
    on_mover = lambda p: np.hypot(p[:, 0] - 3.0, p[:, 1]) < 0.3  # noqa: E731
    assert not on_mover(drawn).any() and not on_mover(loc.static_points).any()
    assert len(drawn) == len(loc.static_points) + 40


def _open_room_scan(x, cart_x=None, n=360):
    """From (x, 0) facing +x (x within a metre of the origin): the west half
    of an oval room (4 m by 3 m), open ground to the east (no return), and a
    cart's near face at ``cart_x`` straight ahead; ranges, angles."""
    a = -np.pi + 2 * np.pi / n * np.arange(n)
    west = np.abs(a) > np.pi / 2
    qa, qb, qc = (np.cos(a) / 4) ** 2 + (np.sin(a) / 3) ** 2, x * np.cos(a) / 16, x * x / 16 - 1
    r = np.where(west, (-qb + np.sqrt(qb * qb - qa * qc)) / qa, np.inf)  # the beam meets the oval
    if cart_x is not None:
        r[np.abs(a) < 0.05] = cart_x - x
    return r, a


def test_beams_without_a_return_clear_a_cart_that_drove_off_from_the_live_map(tmp_path):
    """A cart seen 8 m off against open ground, then gone: the scans'
    beams that came back with nothing (RobotLocaliser.free_points) cross
    its cells, so the map drops it; from the returns alone it stayed."""
    from app.core.localisation.free_space import no_return_rays

    maps = {}
    for use_free in (True, False):
        m = MappingMode(tmp_path)
        m.start()
        for k in range(20):  # 0.05 m per scan; the cart there for the first five
            r, a = _open_room_scan(0.05 * k, 8.0 if k < 5 else None)
            ok = np.isfinite(r)
            pts = np.column_stack((r[ok] * np.cos(a[ok]), r[ok] * np.sin(a[ok])))
            free = no_return_rays(r, a, 11.9) if use_free else None
            m.add((0.05 * k, 0.0, 0.0), pts, None, free)
        maps[use_free] = m.grid()
    for use_free, g in maps.items():
        occ = np.argwhere(g.occupied)
        xy = np.column_stack((g.origin_xy[0] + (occ[:, 1] + 0.5) * g.resolution_m,
                              g.origin_xy[1] + (occ[:, 0] + 0.5) * g.resolution_m))
        cart = (xy[:, 0] > 7.0) & (np.abs(xy[:, 1]) < 1.0)
        assert cart.any() != use_free  # gone with the free rays, kept without
        assert (xy[:, 0] < -3.0).sum() > 20  # the room's west wall stays either way


def test_the_localiser_hands_the_beams_without_a_return_to_the_map():
    import math

    from sim_robot.localisation import RobotLocaliser, load_station_map

    start = (62.9, 45.0, math.pi)
    loc = RobotLocaliser(load_station_map(), start)
    assert len(loc.free_points()) == 0  # no scan yet
    loc.predict(start)
    n = 360
    ranges = np.full(n, 3.0, np.float32)
    ranges[100:140] = np.inf  # open ground through a gap
    scan = P.LidarScan(0, -math.pi, 2 * math.pi / n, 12.0, ranges)
    loc.predict((start[0] - 0.1, start[1], start[2]))  # moved: the scan is fused
    loc.correct(scan)
    free = loc.free_points()
    length = np.hypot(free[:, 0], free[:, 1])
    assert len(free) == 40
    bearing = np.arctan2(free[:, 1], free[:, 0])
    gap = -math.pi + 2 * math.pi / n * np.arange(100, 140)
    assert np.allclose(np.sort(bearing), gap, atol=1e-6)
    assert np.isclose(length.max(), 11.9 - 0.3) and np.isclose(length.min(), 3.0 - 0.3)


def test_a_wall_seen_at_a_grazing_angle_stays_in_the_map():
    """A wall 1 m beside the robot's path, seen 2-10 m ahead: beams that end
    farther along it cross the corners of its nearer cells more often than
    beams end in them. At the logs' miss weight (a cell is a wall while hits
    are over 40 % of the beams through it) a third of it wore away; the
    mapping mode's map (GMapping's 25 %, MAP_L_FREE) keeps it."""
    from app.core.localisation.map_io import build_grid
    from sim_robot.mapping_mode import MapView
    from tests.localisation.test_map_io import _drive_past_wall

    # 1 m along x at 0.05 m a scan, the wall at y = 1.03 m
    poses, scans, free = _drive_past_wall(1.03)

    def wall_kept(g):
        """Share of the wall's 0.1 m stretches 2-10 m ahead with an occupied
        cell in its row or the next."""
        row = int(np.floor((1.03 - g.origin_xy[1]) / g.resolution_m))
        cols = np.floor((np.arange(2.05, 10.0, 0.1) - g.origin_xy[0]) / g.resolution_m)
        return float((g.cells[row - 1:row + 2, cols.astype(int)] == 100).any(axis=0).mean())

    logs = build_grid(poses, scans, 0.1, free_scans=free)  # l_free -0.6
    mode = MapView(poses, scans, 0.1, free).grid()
    assert wall_kept(logs) < 0.75
    assert wall_kept(mode) > 0.85
