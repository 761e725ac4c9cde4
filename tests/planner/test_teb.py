"""Optimised TEB (seed 004 §2.3): no reverse steps, in-place turns past 30°,
re-sizing with hysteresis, the laser-odometry hook, and the seed's scenes."""

import math

import numpy as np
import pytest

from app.core.planner.teb import ObstacleField, Teb, TebConfig
from app.core.planner.teb_scenes import run_scene

pytestmark = pytest.mark.slow(32)

OPEN = ObstacleField(np.zeros((100, 100), dtype=bool), 0.05)


def _straight(length=3.0):
    return np.column_stack([np.linspace(0, length, 31) + 0.5, np.full(31, 2.5)])


def test_turns_in_place_past_30_degrees_and_drives_below():
    path = _straight()
    goal = np.array([3.5, 2.5, 0.0])
    for off_deg, pivot in [(90, True), (-45, True), (20, False), (0, False)]:
        teb = Teb(TebConfig())
        step = teb.plan_step((0.5, 2.5, math.radians(off_deg)), goal, path, OPEN, 0.0, True)
        assert step.turning_in_place is pivot
        if pivot:
            assert step.twist.vx == 0.0 and step.twist.vy == 0.0
            assert math.copysign(1, step.twist.omega) == -math.copysign(1, off_deg)
        else:
            assert step.twist.vx > 0.0


def test_plain_teb_has_no_in_place_turn():
    teb = Teb(TebConfig(optimised=False))
    pose = (0.5, 2.5, math.radians(90))
    step = teb.plan_step(pose, (3.5, 2.5, 0.0), _straight(), OPEN, 0.0, True)
    assert not step.turning_in_place


def test_resizing_keeps_a_dead_band():
    cfg = TebConfig(dt_ref_s=0.3, dt_hyst_s=0.1)
    teb = Teb(cfg)
    teb.poses = np.column_stack([np.arange(6.0), np.zeros(6), np.zeros(6)])
    teb.dts = np.array([0.3, 0.45, 0.25, 0.1, 0.35])
    teb._resize()
    # 0.45 > 0.4: split in two; 0.1 < 0.2: merged with the next (0.45);
    # 0.25 and 0.35 lie inside the dead band and stay.
    assert np.allclose(teb.dts, [0.3, 0.225, 0.225, 0.25, 0.45])
    assert len(teb.poses) == len(teb.dts) + 1
    assert teb.poses[2, 0] == pytest.approx(1.5)


def test_pose_correction_hook_sets_the_band_start():
    seen = []

    def correct(p):
        seen.append(tuple(p))
        return np.asarray(p) + np.array([0.1, -0.05, 0.0])

    teb = Teb(TebConfig(), pose_correction=correct)
    step = teb.plan_step((0.5, 2.5, 0.0), (3.5, 2.5, 0.0), _straight(), OPEN, 0.0, True)
    assert seen == [(0.5, 2.5, 0.0)]
    assert np.allclose(step.poses[0], (0.6, 2.45, 0.0))


@pytest.mark.parametrize("scene", ["l_dead_end", "obstacle_at_goal"])
def test_optimised_teb_reaches_the_goal_without_reversing(scene):
    res = run_scene(scene, optimised=True)
    assert res.reached
    assert res.reverse_m == 0.0
    assert res.band_min_speed_mps > -0.02  # no reverse step planned either
    assert res.min_clearance_m > 0.4  # robot radius 0.39 m: no contact
    if scene == "l_dead_end":  # it faces the closed end: it must turn in place
        assert res.turns_in_place > 0


def test_plain_teb_backs_out_of_the_dead_end():
    res = run_scene("l_dead_end", optimised=False)
    assert res.reverse_m > 0.5
