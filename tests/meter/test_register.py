"""Registration of a frame to a calibrated point's reference frame: known homographies are
recovered, a wrong reference is refused, and the CLI reads with a reference image given
relative to the profile file."""

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from app.core.meter import load_profile, make_calibrated_profile, read_gauge
from app.core.meter.register import (
    carry_points,
    implausible,
    reference_features,
    reference_image,
    register,
)
from sim_robot.gauge_render import STOCK_SPECS, render_view

ROOT = Path(__file__).resolve().parents[2]
SPEC = STOCK_SPECS[1]  # 0-1.6 MPa, 270 deg
FS = SPEC.max_value - SPEC.min_value
VIEW = dict(fill=0.6, tilt_deg=12, tilt_axis_deg=40, roll_deg=4, noise_sigma=2.0,
            offset_frac=(0.03, -0.02))


def _dial_px(h, x, y):
    q = np.asarray(h) @ np.array([x, y, 1.0])
    return [float(q[0] / q[2]), float(q[1] / q[2])]


def _reference(tmp_path, seed=5, value=0.3):
    """A reference frame on disk and the true clicks on it (pivot, end marks)."""
    img, truth = render_view(SPEC, value, rng=np.random.default_rng(seed), **VIEW)
    (tmp_path / "ref").mkdir(exist_ok=True)
    cv2.imwrite(str(tmp_path / "ref" / "pg.png"), img)
    h = truth["homography"]
    size = int(round(0.6 * 480 / 0.98))
    size += size % 2
    c, r = size / 2, 0.37 * size

    def end(a):
        return _dial_px(h, c + r * math.sin(math.radians(a)), c - r * math.cos(math.radians(a)))

    clicks = (_dial_px(h, c, c), end(SPEC.min_angle_deg), end(SPEC.max_angle_deg))
    d = make_calibrated_profile(SPEC.profile(), *clicks, image="ref/pg.png")
    return img, clicks, d


def _revisit(value, seed, warp):
    """The same point seen again: the scene re-rendered with the needle at ``value``, then
    moved by the homography ``warp`` (the robot stopped a little elsewhere)."""
    img, _ = render_view(SPEC, value, rng=np.random.default_rng(seed), **VIEW)
    return cv2.warpPerspective(img, warp, (640, 480), borderMode=cv2.BORDER_REPLICATE)


def _warp(angle_deg, scale, tx, ty, px=0.0, py=0.0):
    a = math.radians(angle_deg)
    t = np.array([[1, 0, 320], [0, 1, 240], [0, 0, 1.0]])
    m = np.array([[scale * math.cos(a), -scale * math.sin(a), tx],
                  [scale * math.sin(a), scale * math.cos(a), ty], [px, py, 1.0]])
    return t @ m @ np.linalg.inv(t)


@pytest.mark.parametrize("warp", [
    (0.0, 1.0, 0.0, 0.0),
    (4.0, 1.05, 25.0, -12.0),
    (-6.0, 0.92, -30.0, 18.0, 6e-5, -4e-5),
], ids=["same", "moved", "moved-perspective"])
def test_registration_carries_known_points(tmp_path, warp):
    _, clicks, d = _reference(tmp_path)
    prof = load_profile(d, base_dir=tmp_path)
    w = _warp(*warp)
    frame = _revisit(1.1, 5, w)
    reg = register(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY), prof.calibration)
    assert reg.ok, reg.error
    got = carry_points(reg.homography, clicks)
    want = carry_points(w, clicks)
    assert np.abs(got - want).max() < 1.0
    r = read_gauge(frame, prof)
    assert r.method == "calibrated-reference" and r.value is not None, r.error
    assert r.value == pytest.approx(1.1, abs=0.01 * FS)
    assert "registration" in r.scores and np.asarray(r.homography).shape == (3, 3)
    assert math.dist(r.dial_centre_xy, want[0]) < 1.0
    assert math.dist(r.scale_ends_xy[1], want[2]) < 1.0


def test_a_wrong_reference_is_refused(tmp_path):
    _, _, d = _reference(tmp_path)
    prof = load_profile(d, base_dir=tmp_path)
    # another scene altogether: a different gauge type in different surroundings
    other, _ = render_view(STOCK_SPECS[2], 5.0, rng=np.random.default_rng(99),
                           **{**VIEW, "offset_frac": (-0.1, 0.05)})
    r = read_gauge(other, prof)
    assert r.value is None and r.error.startswith("registration failed"), r.error
    assert r.method == "calibrated-reference" and r.homography is None
    blank = np.full((480, 640, 3), 128, np.uint8)
    r = read_gauge(blank, prof)
    assert r.value is None and r.error.startswith("registration failed")


def test_implausible_warps_are_named():
    c, rad, shape = (320.0, 240.0), 100.0, (480, 640)
    pts = [c, (250.0, 300.0), (390.0, 300.0)]

    def why(h):
        return implausible(np.asarray(h, float), c, rad, shape, carry_points(h, pts))

    assert why(np.eye(3)) is None
    assert "mirrored" in why(np.diag([-1.0, 1.0, 1.0]) @ _warp(0, 1, 640, 0))
    assert "scale" in why(_warp(0, 2.6, 0, 0))
    assert "shear or tilt" in why(np.array([[1.9, 0.0, -300], [0.0, 1.0, 0], [0, 0, 1.0]]))
    t = 1e-3  # a vanishing line about 700 px from the dial, which stays where it was
    tilt = np.array([[1.0, 0, -t * c[0] ** 2], [0, 1.0, -t * c[0] * c[1]], [t, 0, 1 - t * c[0]]])
    assert "perspective" in why(tilt)
    assert "leave the image" in why(_warp(0, 1, 300, 0))


def test_reference_is_cached_until_the_file_changes(tmp_path):
    img, clicks, _ = _reference(tmp_path)
    path = tmp_path / "ref" / "pg.png"
    f1 = reference_features(path, clicks[0], 100.0)
    assert reference_features(path, clicks[0], 100.0) is f1
    assert reference_image(path) is reference_image(path)
    # every keypoint lies in the dial region (1.4 x the pivot-to-end-mark distance)
    assert np.hypot(*(f1[0] - np.asarray(clicks[0])).T).max() <= 1.4 * 100.0 + 1
    cv2.imwrite(str(path), cv2.flip(img, 1))
    st = path.stat()
    os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))
    assert reference_features(path, clicks[0], 100.0) is not f1
    path.write_text("broken")
    with pytest.raises(ValueError, match="pg.png: not a readable image"):
        reference_image(path)


def test_cli_reads_with_a_reference_relative_to_the_profile(tmp_path):
    _, _, d = _reference(tmp_path)
    (tmp_path / "pg.json").write_text(json.dumps(d))
    frames = []
    for i, v in enumerate((0.4, 1.45)):
        p = tmp_path / f"f{i}.png"
        cv2.imwrite(str(p), _revisit(v, 5, _warp(2.0 * i, 1.0, 10.0 * i, 5.0)))
        frames.append(p)
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"\x89PNG broken")
    # run elsewhere: the reference is found next to the profile, not in the cwd
    r = subprocess.run([sys.executable, "-m", "app.core.meter", "read", "--profile",
                        str(tmp_path / "pg.json"), str(frames[0]), str(bad), str(frames[1])],
                       capture_output=True, text=True, cwd=tmp_path, timeout=60,
                       env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert r.returncode == 1, r.stderr
    lines = [json.loads(s) for s in r.stdout.strip().splitlines()]
    assert [x["image"] for x in lines] == [str(frames[0]), str(bad), str(frames[1])]
    assert lines[0]["value"] == pytest.approx(0.4, abs=0.01 * FS)
    assert lines[2]["value"] == pytest.approx(1.45, abs=0.01 * FS)
    assert lines[1]["value"] is None and lines[1]["error"] == "not an image"


def test_matches_bunched_in_one_part_of_the_dial_are_refused(tmp_path):
    img, clicks, d = _reference(tmp_path)
    prof = load_profile(d, base_dir=tmp_path)
    (cx, cy), (mx, my) = clicks[0], clicks[1]
    rad = math.hypot(mx - cx, my - cy)
    # only a patch of the dial around its minimum mark is left; the rest is flat grey
    part = np.full_like(img, 128)
    x0, y0 = int(mx - 0.45 * rad), int(my - 0.45 * rad)
    x1, y1 = int(mx + 0.45 * rad), int(my + 0.45 * rad)
    part[y0:y1, x0:x1] = img[y0:y1, x0:x1]
    reg = register(cv2.cvtColor(part, cv2.COLOR_BGR2GRAY), prof.calibration)
    assert not reg.ok and reg.homography is None
    # enough inliers to fit, but all in one corner: the warp of the rest is not known
    assert reg.n_inliers >= 25 and "only part of the dial" in reg.error, reg.error
    # the whole frame registers (the check above is the patch's, not the reference's)
    assert register(cv2.cvtColor(img, cv2.COLOR_BGR2GRAY), prof.calibration).ok
