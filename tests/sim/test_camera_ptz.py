"""The pan-tilt-zoom inspection view: the meter reader reads the true value from it."""

import math

import numpy as np
import pytest

from app.core.meter import load_profile, read_gauge
from app.core.paths import resource
from sim_robot.camera import Camera
from sim_robot.ptz import mount_roll_deg, ptz_geometry
from sim_robot.world import World


@pytest.fixture(scope="module")
def world():
    return World(seed=1)


def _pose(g, standoff, off_rad):
    a = g.facing_rad + off_rad
    return g.x + standoff * math.cos(a), g.y + standoff * math.sin(a), a + math.pi


@pytest.mark.parametrize("gid,standoff,off,t_s", [
    ("PG-102", 1.2, 0.0, 30.0),
    ("PG-102", 1.8, 0.35, 210.0),
    ("PG-101", 1.0, -0.4, 95.0),
    ("PG-201", 2.2, 0.25, 400.0),
    ("CG-301", 1.4, -0.2, 50.0),
])
def test_ptz_view_reads_true_value(world, gid, standoff, off, t_s):
    cam = Camera(world)
    g = next(g for g in world.gauges if g.id == gid)
    prof = load_profile(resource("gauges", f"{g.type}.json"))
    cam.set_target(gid)
    img = cam.render(*_pose(g, standoff, off), t_s)
    assert img.shape == (480, 640, 3) and img.dtype == np.uint8
    r = read_gauge(img, prof)
    assert r.value is not None, r.error
    assert abs(r.value - g.value(t_s)) <= 0.01 * (g.max - g.min)


def test_ptz_geometry_follows_the_pose(world):
    g = next(g for g in world.gauges if g.id == "PG-101")
    head_on = ptz_geometry(g, *_pose(g, 1.2, 0.0)[:2])
    side = ptz_geometry(g, *_pose(g, 1.2, 0.5)[:2])
    behind = ptz_geometry(g, *_pose(g, 1.2, math.pi)[:2])
    assert head_on.visible and side.visible and not behind.visible
    assert side.tilt_deg > head_on.tilt_deg + 20
    assert head_on.roll_deg == mount_roll_deg("PG-101") == ptz_geometry(g, 0.0, 0.0).roll_deg
    assert 0.5 <= ptz_geometry(g, *_pose(g, 4.0, 0.0)[:2]).fill <= head_on.fill <= 0.7


def test_no_target_is_the_normal_view(world):
    cam = Camera(world)
    g = next(g for g in world.gauges if g.id == "PG-102")
    pose = _pose(g, 1.2, 0.0)
    normal = cam.render(*pose, 10.0)
    cam.set_target("PG-102")
    zoomed = cam.render(*pose, 10.0)
    cam.set_target(None)
    again = cam.render(*pose, 10.0)
    assert np.array_equal(normal, again)
    assert np.abs(zoomed.astype(int) - normal.astype(int)).mean() > 10
    with pytest.raises(ValueError):
        cam.set_target("NO-SUCH")


def test_lighting_and_motion_change_the_view(world):
    cam = Camera(world)
    g = next(g for g in world.gauges if g.id == "PG-201")
    cam.set_target(g.id)
    x, y, th = _pose(g, 1.2, 0.0)
    day = cam.render(x, y, th, 3 * 3600.0).astype(float).mean()  # noon (starts 9:00)
    night = cam.render(x, y, th, 14 * 3600.0).astype(float).mean()  # 23:00
    assert night < 0.8 * day
    cam.render(x, y, th, 100.1)
    still = cam.render(x, y, th, 100.2)
    moving = cam.render(x + 0.06, y, th + 0.05, 100.3)
    lap = lambda im: float(np.abs(np.diff(im.astype(np.int16), axis=1)).mean())  # noqa: E731
    assert lap(moving) < lap(still)
