"""The synthetic CARMEN logs of bench/synth_carmen.py: read back by the
CARMEN reader with their beam counts and bearings, scans whose geometry
scan matching recovers, and a small loop the mapper closes."""

import math

import numpy as np
import pytest

from app.core.localisation.carmen import read_log
from app.core.localisation.evaluate import ate_m, drifting_odometry
from app.core.localisation.icp import Reference, match
from app.core.localisation.mapping import MappingConfig
from app.core.localisation.se2 import relative, wrap
from app.core.localisation.slam import log_odometry, run_mapping, scan_points
from bench.synth_carmen import LogSpec, draw_at, write_log
from bench.synth_world import dense_poses, sample_scans, world_from_blocked


def _room():
    """A 14 m x 9 m hall (0.2 m cells) round a 6 m x 2 m block, an L-shaped
    wall and some posts: every scan sees corners."""
    b = np.zeros((45, 70), bool)
    b[18:28, 20:50] = True  # the block
    b[5:7, 8:16] = True
    b[5:12, 8:10] = True  # an L
    for c in (30, 36, 42, 56):
        b[38:40, c:c + 2] = True  # posts
    b[8:10, 58:64] = True
    return world_from_blocked(b, 0.2)


def _loop_poses(laps=1):
    """A loop round the block, about 0.8 m between scans, up to 45 deg turns."""
    corners = np.array([[2.5, 2.5], [11.5, 2.5], [11.5, 6.5], [2.5, 6.5], [2.5, 2.5]])
    path = np.vstack([corners] * laps)
    dense = np.vstack([np.linspace(a, b, max(2, int(np.hypot(*(b - a)) / 0.05)))
                       for a, b in zip(path[:-1], path[1:], strict=True)])
    return sample_scans(dense_poses(dense), 0.8, 45.0, seed=3)


@pytest.fixture(scope="module")
def room():
    return _room()


def _spec(beams, no_return=81.9):
    return LogSpec("test", False, "test", None, 0.2, 0.4, beams, no_return, 80.0,
                   timestamps="repeat", dropout=0.02, fov_param=beams % 2 == 1)


@pytest.mark.parametrize("beams", [180, 181, 360, 361])
def test_the_reader_reads_the_drawn_beams_where_they_were_cast(tmp_path, room, beams):
    ref = _loop_poses()[:6]
    drawn = draw_at(room, ref, beams, 80.0, seed=1)
    odo = drifting_odometry(ref, seed=2)
    spec = _spec(beams, 50.0 if beams == 181 else 81.9)
    write_log(tmp_path / "a.log", spec, drawn, odo, seed=4)
    log = read_log(tmp_path / "a.log")
    assert not log.bad_lines and len(log.scans) == 6 and len(log.odometry) == 10
    assert all(s.ranges_m.size == beams for s in log.scans)
    np.testing.assert_allclose(log.beam_angles(beams), drawn.angles, atol=1e-12)
    step = math.radians(1.0 if beams < 300 else 0.5)  # 1 deg or 0.5 deg, from the right
    np.testing.assert_allclose(np.diff(drawn.angles), step, atol=1e-12)
    assert drawn.angles[0] == pytest.approx(-math.pi / 2)
    assert abs(log.no_return_m() - spec.no_return_m) < 0.01 * spec.no_return_m
    # the odometry is written in a frame of its own; its motions are the drawn ones
    got = log_odometry(log)
    want = np.array([relative(odo[0], p) for p in odo])
    np.testing.assert_allclose(got[:, :2], want[:, :2], atol=2e-5)
    assert np.all(np.abs(wrap(got[:, 2] - want[:, 2])) < 2e-5)


def test_scan_matching_recovers_the_drawn_motion_between_scans(tmp_path, room):
    """A mirrored bearing, a wrong beam step or a frame error in the generator
    would leave ICP (started from drifting odometry) off the drawn motion."""
    ref = _loop_poses()
    odo = drifting_odometry(ref, seed=5)
    drawn = draw_at(room, ref, 361, 80.0, seed=6)
    write_log(tmp_path / "b.log", _spec(361), drawn, odo, seed=7)
    log = read_log(tmp_path / "b.log")
    pts = scan_points(log)
    odom = log_odometry(log)
    turned = 0
    for k in range(1, len(ref)):
        truth = relative(ref[k - 1], ref[k])
        r = match(pts[k], Reference(pts[k - 1]), relative(odom[k - 1], odom[k]),
                  window_xy_m=0.5, window_theta_rad=math.radians(15))
        assert math.hypot(*(r.pose[:2] - truth[:2])) < 0.03, k
        assert abs(math.degrees(wrap(r.pose[2] - truth[2]))) < 0.5, k
        turned += abs(truth[2]) > math.radians(20)
    assert turned >= 4  # the corners were matched too


def test_the_mapper_closes_a_drawn_loop(tmp_path, room):
    ref = _loop_poses(laps=2)
    odo = drifting_odometry(ref, seed=8)
    drawn = draw_at(room, ref, 181, 80.0, seed=9)
    write_log(tmp_path / "c.log", _spec(181, 50.0), drawn, odo, seed=10)
    log = read_log(tmp_path / "c.log")
    # the command line's configuration: loop closure and the final pass
    est, mapper = run_mapping(scan_points(log), log_odometry(log), MappingConfig(final_pass=True))
    truth = np.array([relative(ref[0], p) for p in ref])
    assert ate_m(odo, ref) > 1.0
    assert ate_m(est, truth) < 0.04
    assert mapper.loop_closures >= 1
