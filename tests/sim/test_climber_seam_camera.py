"""The climber's seam camera as pixels: frames drawn from the simulated wall
(sim_robot/climber/camera_view.py), the seams and the shell's edges found in
them (app/core/localisation/seam_camera.py), and the relay fixing its
estimate on what it finds."""

from __future__ import annotations

import math
import time

import cv2
import numpy as np
import pytest

from app.core.localisation.seam_camera import find_lines, lines_to_sightings
from app.core.planner.coverage.wall import Disc, WallSpec, plate_seams
from sim_robot.climber.camera_view import M_PER_PX, render_view
from sim_robot.climber.wall_world import WallWorld


@pytest.fixture(scope="module")
def world():
    d = 6.0 / math.pi
    spec = WallSpec(d, 2.4, 0.1, nozzles=(Disc(4.2, 1.8, 0.3),),
                    seams=plate_seams(d, 2.4, course_m=1.2, plates=2))
    return WallWorld(spec, 10.0, (), seed=1)


def _seen(world, x, y, th, rng, heading_error=0.0):
    img = render_view(world, x, y, th, rng)
    return lines_to_sightings(find_lines(img, M_PER_PX), th + heading_error)


@pytest.mark.parametrize("theta_deg", [0.0, 90.0, -90.0, 180.0, 33.0, -140.0])
def test_a_girth_seam_is_found_where_it_is(world, theta_deg):
    """The girth seam at y = 1.2 m, 37 mm above the image centre, at any
    heading: one horizontal line, 37 mm up, in the direction it lies."""
    rng = np.random.default_rng(int(theta_deg) + 200)
    th = math.radians(theta_deg)
    (horizontal, angle, offset), = _seen(world, 1.0, 1.2 - 0.037, th, rng)
    assert horizontal and offset == pytest.approx(0.037, abs=0.002)
    err = (angle - (0.0 - th) + math.pi / 2) % math.pi - math.pi / 2
    assert abs(err) < math.radians(1.0)


def test_the_shell_edges_and_a_vertical_seam(world):
    rng = np.random.default_rng(5)
    # the top edge 50 mm above, facing up
    (h, _, off), = _seen(world, 1.0, 2.4 - 0.05, math.pi / 2, rng)
    assert h and off == pytest.approx(0.05, abs=0.002)
    # the bottom edge's fillet weld 30 mm below, facing along the row
    (h, _, off), = _seen(world, 1.0, 0.03, 0.0, rng)
    assert h and off == pytest.approx(-0.03, abs=0.002)
    # the lower course's vertical seam at x = 0 (the tank's own seam), 25 mm left of
    # the centre as the wall's x goes, facing up
    seen = _seen(world, 0.025, 0.6, math.pi / 2, rng)
    (h, _, off), = seen
    assert not h and off == pytest.approx(-0.025, abs=0.002)


def test_plain_plate_and_a_nozzles_rim_give_no_line(world):
    rng = np.random.default_rng(9)
    for k in range(20):
        assert _seen(world, 0.8 + 0.05 * k, 0.45, rng.uniform(-3, 3), rng) == []
    # the nozzle at (4.2, 1.8), r 0.15: its rim across the image is curved, no line
    for a in np.linspace(0, 2 * math.pi, 8, endpoint=False):
        x, y = 4.2 + 0.17 * math.cos(a), 1.8 + 0.17 * math.sin(a)
        assert _seen(world, x, y, 0.3, rng) == []


def test_found_lines_agree_with_the_geometry_over_random_views(world):
    """Over random poses, half of them near the girth seam or an edge: the lines
    found in the frames match the simulator's geometric sightings within 2 mm,
    and no line is found where none is within the image (a 5 mm border left for
    lines leaving the view at its edge)."""
    rng = np.random.default_rng(11)
    matched = missed = spurious = 0
    for k in range(120):
        x, y = rng.uniform(0, world.circ_m), rng.uniform(0.02, 2.38)
        if k % 2 == 0:
            y = float(np.clip(rng.choice([0.0, 1.2, 2.4]) + rng.uniform(-0.06, 0.06), 0.02, 2.38))
        th = rng.uniform(-math.pi, math.pi)
        truth = world.seam_sightings(x, y, th, rng, offset_noise_m=0.0, angle_noise_rad=0.0,
                                     range_m=0.065)
        wide = world.seam_sightings(x, y, th, rng, offset_noise_m=0.0, angle_noise_rad=0.0,
                                    range_m=0.085)
        seen = _seen(world, x, y, th, rng, heading_error=math.radians(rng.normal(0, 1)))
        for h, _, off in truth:
            if any(h2 == h and abs(o2 - off) < 0.002 for h2, _, o2 in seen):
                matched += 1
            else:
                missed += 1
        for h, _, off in seen:
            if not any(h2 == h and abs(o2 - off) < 0.005 for h2, _, o2 in wide):
                spurious += 1
    assert matched >= 60 and missed <= 0.05 * (matched + missed) and spurious == 0


def test_a_seam_drawn_otherwise_dark_and_coarser_is_found():
    """Not the simulator's drawing: a flat plate, a dark bead drawn with OpenCV,
    1.5 mm a pixel, JPEG-compressed. The bead's axis is found all the same."""
    rng = np.random.default_rng(3)
    img = np.full((120, 120), 150, np.uint8)
    # a dark bead 14 px (21 mm) wide, through (70, 60) at 20° from the image's x axis
    c, s = math.cos(math.radians(20)), math.sin(math.radians(20))
    p0 = (int(70 - 200 * c), int(60 - 200 * s))
    p1 = (int(70 + 200 * c), int(60 + 200 * s))
    cv2.line(img, p0, p1, 95, 14, cv2.LINE_AA)
    img = np.clip(img + rng.normal(0, 4, img.shape), 0, 255).astype(np.uint8)
    img = cv2.imdecode(cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 70])[1], 0)
    (line,) = find_lines(img, 0.0015)
    assert line.kind == "bead"
    # the axis passes through pixel (70, 60): 10.5 px right of the centre, 0.5 px up
    u, v = 70 - 59.5, 60 - 59.5
    # distance from that point to the found line (body frame: fwd = −v, left = −u)
    fwd, left = -v * 0.0015, -u * 0.0015
    d = (fwd - line.fwd_m) * math.cos(line.angle_rad + math.pi / 2) + \
        (left - line.left_m) * math.sin(line.angle_rad + math.pi / 2)
    assert abs(d) < 0.0015
    # the image direction (cos 20°, sin 20°) (x right, y down) is the body direction
    # (fwd, left) = (−sin 20°, −cos 20°), that is (sin 20°, cos 20°) modulo π
    want = math.atan2(c, s) % math.pi
    err = (line.angle_rad - want + math.pi / 2) % math.pi - math.pi / 2
    assert abs(err) < math.radians(1.5)


def test_the_relay_fixes_on_seams_it_finds_in_the_pixels():
    """``ClimberSim(seam_camera="pixels")``: the relay gets frames, not sightings;
    it finds the seams in them and its estimate is fixed on them."""
    from app.comm import protocol as P
    from sim_robot.climber.sim import ClimberSim
    from sim_robot.config import SimConfig

    from .test_climber_link import small_setup

    with pytest.raises(ValueError, match="seam camera"):
        ClimberSim(SimConfig(video=False), small_setup(), seam_camera="oracle")
    sim = ClimberSim(SimConfig(video=False, seed=2, time_scale=10.0), small_setup(),
                     seam_camera="pixels")
    assert sim.relay.seams_seen is None and sim.relay.seam_frames is not None
    sim.start()
    try:
        ok, why = sim.relay.handle_command(P.Command("start_inspection", {}), None)
        assert ok, why
        deadline = time.monotonic() + 60
        while sim.relay.counters["seam_fixes"] < 5 and time.monotonic() < deadline:
            time.sleep(0.1)
        assert sim.relay.counters["frames"] > 0 and sim.relay.counters["seam_fixes"] >= 5
    finally:
        sim.close()


def test_a_nozzles_rim_is_found_at_its_nearest_point(world):
    """The nozzle at (4.2, 1.8), r 0.15: from points round it, inside and outside its
    rim, the offset to the rim's nearest point in the body frame, within 1 mm; a
    seam and plain plate give no rim."""
    from app.core.localisation.rim_camera import find_rims

    rng = np.random.default_rng(21)
    found = 0
    for k in range(24):
        a = 2 * math.pi * k / 24
        rr = 0.15 + (0.04 if k % 2 else -0.03)
        x, y = 4.2 + rr * math.cos(a), 1.8 + rr * math.sin(a)
        th = rng.uniform(-math.pi, math.pi)
        (want,) = world.rim_sightings(x, y, th, rng, noise_m=0.0, angle_noise_rad=0.0)
        seen = find_rims(render_view(world, x, y, th, rng), M_PER_PX, [0.15, 0.3])
        assert len(seen) <= 1
        if seen:
            assert math.dist(seen[0][:2], want[:2]) < 0.001  # the nearest point
            assert math.dist(seen[0][2:], want[2:]) < 0.002  # the centre, 15-19 cm away
            found += 1
    assert found >= 22
    for y in (1.2 - 0.03, 0.5, 0.03):  # the girth seam, plain plate, the bottom edge
        assert find_rims(render_view(world, 1.0, y, 0.4, rng), M_PER_PX, [0.15, 0.3]) == []


def test_a_rim_drawn_otherwise_is_found():
    """Not the simulator's drawing: a dark disc of radius 200 px (0.3 m at 1.5 mm a
    pixel) on a lighter plate, its edge 30 px from the image centre, JPEG-compressed."""
    from app.core.localisation.rim_camera import find_rims

    rng = np.random.default_rng(2)
    img = np.full((140, 140), 140, np.uint8)
    ox = oy = 69.5
    # the disc's centre 230 px from the image centre, down and to the left
    u = np.array([-0.6, 0.8])
    cx, cy = ox + 230 * u[0], oy + 230 * u[1]
    yy, xx = np.mgrid[0:140, 0:140]
    img[np.hypot(xx - cx, yy - cy) < 200] = 60
    img = cv2.GaussianBlur(img, (0, 0), 1.0)
    img = np.clip(img + rng.normal(0, 4, img.shape), 0, 255).astype(np.uint8)
    img = cv2.imdecode(cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 70])[1], 0)
    (seen,) = find_rims(img, 0.0015, [0.3])
    qx, qy = ox + 30 * u[0], oy + 30 * u[1]  # the rim's nearest point, in pixels
    want = (-(qy - oy) * 0.0015, -(qx - ox) * 0.0015)
    assert math.dist(seen[:2], want) < 0.0015
    assert math.dist(seen[2:], (-(cy - oy) * 0.0015, -(cx - ox) * 0.0015)) < 0.003
