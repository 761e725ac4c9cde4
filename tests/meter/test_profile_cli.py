"""Profiles (load/validate/calibrate/save), fusion and the command line."""

import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from app.core.meter import MeterFusion, Reading, calibrate_profile, load_profile, save_profile
from app.core.paths import resource
from sim_robot.gauge_render import STOCK_SPECS, render_dial

ROOT = Path(__file__).resolve().parents[2]
GAUGES = resource("gauges")


def test_stock_profiles_load_and_paper_table_is_exact():
    names = {p.stem for p in GAUGES.glob("*.json")}
    assert {s.profile_file[:-5] for s in STOCK_SPECS} <= names
    p = load_profile(GAUGES / "paper_0_4mpa.json")
    assert len(p.ticks) == 41
    assert p.ticks[0] == (0.0, 75.69, 215.91) and p.ticks[-1] == (4.0, 220.71, 219.71)
    assert p.ticks[13] == (1.3, 75.69, 82.09)
    assert p.table_radius == pytest.approx(100, abs=1.5)
    assert p.value_at_angle(p.min_angle_deg) == pytest.approx(0.0, abs=0.01)


@pytest.mark.parametrize("bad, msg", [
    ({"unit": "MPa", "min_value": 0, "max_value": 1, "min_angle_deg": -135,
      "max_angle_deg": 135}, "name"),
    ({"name": "x", "unit": "MPa", "min_value": 1, "max_value": 1, "min_angle_deg": -135,
      "max_angle_deg": 135}, "max_value"),
    ({"name": "x", "unit": "MPa", "min_value": 0, "max_value": 1}, "min_angle_deg"),
    ({"name": "x", "unit": "MPa", "min_value": "0", "max_value": 1, "min_angle_deg": -135,
      "max_angle_deg": 135}, "finite number"),
    ({"name": "x", "unit": "MPa", "min_value": 0, "max_value": 1, "min_angle_deg": 0,
      "max_angle_deg": 2}, "span"),
    ({"name": "x", "unit": "MPa", "min_value": 0, "max_value": 1, "min_angle_deg": -135,
      "max_angle_deg": 135, "normal_min": 0.9, "normal_max": 0.1}, "normal_min"),
    ([1, 2], "JSON object"),
])
def test_bad_profiles_raise_clear_errors(bad, msg):
    with pytest.raises(ValueError, match=msg):
        load_profile(bad)


def test_profile_file_errors(tmp_path):
    with pytest.raises(ValueError, match="no such"):
        load_profile(tmp_path / "missing.json")
    f = tmp_path / "broken.json"
    f.write_text("{not json")
    with pytest.raises(ValueError, match="JSON"):
        load_profile(f)


def test_calibrate_and_save_roundtrip(tmp_path):
    # upright photo: centre (150,150), min tick at 7:30, max tick at 4:30
    d = calibrate_profile((150, 150), (79.3, 220.7), (220.7, 220.7), 0.0, 1.6, "new", "MPa",
                          normal_max=1.2)
    assert d["min_angle_deg"] == pytest.approx(-135, abs=0.1)
    assert d["max_angle_deg"] == pytest.approx(135, abs=0.1)
    path = save_profile(d, tmp_path / "new.json")
    p = load_profile(path)
    assert p.value_at_angle(0.0) == pytest.approx(0.8, abs=1e-3)
    assert p.normal_max == 1.2
    ccw = calibrate_profile((0, 0), (10, 0), (-10, 0), 0, 1, "ccw", "bar", clockwise=False)
    assert ccw["max_angle_deg"] < ccw["min_angle_deg"]


def _r(v, c=0.9):
    return Reading(value=v, unit="MPa", confidence=c)


def test_fusion_rejects_outliers_and_refusals():
    f = MeterFusion(full_scale=4.0, window=7)
    for v in (1.50, 1.51, 1.49, 1.50, 3.2):
        f.add(_r(v))
    f.add(Reading(value=None, unit="MPa", confidence=0.0, error="glare"))
    out = f.fused()
    assert out.value == pytest.approx(1.50, abs=0.006)
    assert out.n_used == 4 and out.n_total == 6
    assert 0.5 <= out.confidence <= 0.9


def test_fusion_says_no_when_frames_disagree_or_too_few():
    f = MeterFusion(full_scale=1.0, min_readings=3)
    f.add(_r(0.1))
    f.add(_r(0.2, 0.3))
    assert f.fused().value is None
    g = MeterFusion(full_scale=1.0)
    for v in (0.1, 0.5, 0.9):
        g.add(_r(v))
    assert g.fused().value is None


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "app.core.meter", *map(str, args)],
                          capture_output=True, text=True, cwd=ROOT, timeout=60)


def test_cli_reads_images_in_order(tmp_path):
    spec = STOCK_SPECS[1]
    paths = []
    for i, v in enumerate((0.4, 1.1)):
        p = tmp_path / f"g{i}.png"
        cv2.imwrite(str(p), render_dial(spec, v))
        paths.append(p)
    blank = tmp_path / "blank.png"
    cv2.imwrite(str(blank), np.full((300, 300, 3), 128, np.uint8))
    r = _cli("read", "--profile", GAUGES / spec.profile_file, paths[0], blank, paths[1])
    assert r.returncode == 0, r.stderr
    lines = [json.loads(s) for s in r.stdout.strip().splitlines()]
    assert [d["image"] for d in lines] == [str(paths[0]), str(blank), str(paths[1])]
    assert lines[0]["value"] == pytest.approx(0.4, abs=0.01)
    assert lines[2]["value"] == pytest.approx(1.1, abs=0.01)
    assert lines[1]["value"] is None and lines[1]["error"]
    assert all(set(d) == {"image", "value", "unit", "confidence", "error"} for d in lines)
    assert lines[0]["unit"] == "MPa" and 0 <= lines[1]["confidence"] <= 1


def test_cli_bad_image_gets_its_own_line_and_the_batch_goes_on(tmp_path):
    prof = GAUGES / "pressure_0_1p6mpa.json"
    good = []
    for i, v in enumerate((0.5, 1.3)):
        p = tmp_path / f"g{i}.png"
        cv2.imwrite(str(p), render_dial(STOCK_SPECS[1], v))
        good.append(p)
    txt = tmp_path / "notimg.png"
    txt.write_text("hello")
    empty = tmp_path / "empty.jpg"
    empty.write_bytes(b"")
    missing = tmp_path / "nope.png"
    r = _cli("read", "--profile", prof, good[0], missing, txt, empty, good[1])
    assert r.returncode == 1, r.stderr
    lines = [json.loads(s) for s in r.stdout.strip().splitlines()]
    assert [d["image"] for d in lines] == list(map(str, (good[0], missing, txt, empty, good[1])))
    assert all(set(d) == {"image", "value", "unit", "confidence", "error"} for d in lines)
    assert lines[0]["value"] == pytest.approx(0.5, abs=0.01)
    assert lines[4]["value"] == pytest.approx(1.3, abs=0.01)
    assert lines[1]["error"] == "no such file" and lines[1]["value"] is None
    assert lines[2]["error"] == "not an image" and lines[3]["error"] == "not an image"
    assert lines[2]["confidence"] == 0 and lines[2]["unit"] == "MPa"
    # a batch of only missing files still answers for each
    r = _cli("read", "--profile", prof, missing)
    assert r.returncode == 1 and json.loads(r.stdout)["error"] == "no such file"


def test_cli_bad_profile_or_arguments_exit_2(tmp_path):
    img = tmp_path / "g.png"
    cv2.imwrite(str(img), render_dial(STOCK_SPECS[1], 0.5))
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"name": "x"}))
    r = _cli("read", "--profile", bad, img)
    assert r.returncode == 2 and "bad profile" in r.stderr and len(r.stderr.splitlines()) == 1
    assert r.stdout == ""
    r = _cli("read", "--profile", tmp_path / "none.json", img)
    assert r.returncode == 2 and "no such profile file" in r.stderr
    r = _cli("read", img)  # no --profile
    assert r.returncode == 2 and r.stdout == ""
    r = _cli("read", "--profile", GAUGES / "pressure_0_1p6mpa.json")  # no image
    assert r.returncode == 2 and r.stdout == ""
    # a calibrated profile whose reference frame is missing is a bad profile
    cal = dict(STOCK_SPECS[1].profile(), calibration={
        "center": [150, 150], "min_point": [70, 230], "max_point": [230, 230],
        "image": "ref/missing.png"})
    path = tmp_path / "cal.json"
    path.write_text(json.dumps(cal))
    r = _cli("read", "--profile", path, img)
    assert r.returncode == 2 and "missing.png" in r.stderr and r.stdout == ""
