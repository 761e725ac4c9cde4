"""Pure pursuit on the 4WS model: a circle, the speed-scheduled look-ahead,
the end of the path, and bad input."""

import math

import numpy as np
import pytest

from app.core.kinematics import Mode, min_turn_radius
from app.core.planner.pure_pursuit import (
    PurePursuit,
    PurePursuitConfig,
    cross_track_error,
    track,
)


def _circle(r, turns=1.0, n=2000, cx=0.0, cy=0.0):
    a = np.linspace(-math.pi / 2, -math.pi / 2 + 2 * math.pi * turns, n)
    return np.column_stack([cx + r * np.cos(a), cy + r * np.sin(a)])


def test_on_the_circle_the_arc_is_the_circle():
    r = 2.0
    pp = PurePursuit(_circle(r), PurePursuitConfig(max_lateral_accel_mps2=10.0))
    tw = pp.command((0.0, -r, 0.0), 0.8)  # on the circle, heading along it
    assert tw.omega / tw.vx == pytest.approx(1.0 / r, rel=2e-3)
    assert tw.vy == 0.0  # counter-phase mode: no crab component


def test_tracks_a_circle_closely():
    r = 2.0
    path = _circle(r, turns=1.25)
    poses, speeds = track(path, PurePursuitConfig(speed_mps=0.8, max_lateral_accel_mps2=0.6))
    err = cross_track_error(path, poses[:, :2])
    assert np.max(speeds) == pytest.approx(min(0.8, math.sqrt(0.6 * r)), rel=1e-3)
    assert np.sqrt(np.mean(err**2)) < 0.03
    assert np.max(err) < 0.06
    end = poses[-1, :2]
    assert np.linalg.norm(end - path[-1]) < 0.1  # stopped at the end


def test_starting_off_the_path_converges():
    path = np.column_stack([np.linspace(0, 12, 200), np.zeros(200)])
    poses, _ = track(path, pose0=(0.0, 0.5, 0.0))
    err = cross_track_error(path, poses[:, :2])
    assert err[0] == pytest.approx(0.5)
    assert np.max(err[len(err) // 2:]) < 0.01


def test_lookahead_grows_with_speed_and_turns_respect_the_limit():
    cfg = PurePursuitConfig()
    assert cfg.lookahead(0.2) < cfg.lookahead(0.8) <= cfg.lookahead_max_m
    assert cfg.lookahead(0.0) >= cfg.lookahead_min_m
    pp = PurePursuit(_circle(0.3), cfg)  # tighter than the base can turn
    tw = pp.command((0.0, -0.3, 0.0), 0.5)
    assert tw.omega / tw.vx <= 1.0 / min_turn_radius(cfg.geometry, Mode.COUNTER) + 1e-9


def test_bad_path_is_refused():
    with pytest.raises(ValueError, match="two distinct points"):
        PurePursuit([(1.0, 1.0), (1.0, 1.0)])
