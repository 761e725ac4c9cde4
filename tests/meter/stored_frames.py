"""Single frames of the bench's image streams, stored as lossless PNG with their truth.

A regression test about one frame deep in a stream (say the 153rd hard image of a
seed) would otherwise render every frame before it to reach it. Each frame here
is named by where it comes from; ``python -m tests.meter.stored_frames`` renders
them again from the streams (bench/meter_why.py's and bench/meter_ab.py's draw)
and rewrites the files.
"""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np

HERE = Path(__file__).resolve().parent / "frames"

# name: (families taken in turn, level, seed, index in the stream[, the bench's row])
FRAMES = {
    "tuning-hard-8-32": ("tuning", "hard", 8, 32),
    "tuning-hard-8-127": ("tuning", "hard", 8, 127),
    "atlas-hard-3-152": (("atlas",), "hard", 3, 152),
    "atlas-field-3-73": (("atlas",), "field", 3, 73),
    "atlas-field-3-102": (("atlas",), "field", 3, 102),
    "atlas-field-2-82": (("atlas",), "field", 2, 82),
    "atlas-field-2-150": (("atlas",), "field", 2, 150),
    "heldout-atlas-field-1-39": (("atlas",), "field", 1, 39, "heldout"),
    "tuning-hard-3-22": ("tuning", "hard", 3, 22),
    "tuning-hard-6-10": ("tuning", "hard", 6, 10),
    "tuning-hard-1-11": ("tuning", "hard", 1, 11),
    "tuning-hard-1-13": ("tuning", "hard", 1, 13),
    "tuning-field-2-30": ("tuning", "field", 2, 30),
    "atlas-clean-1-49": (("atlas",), "clean", 1, 49),
    "process-atlas-clean-1-37": (("process", "atlas"), "clean", 1, 37),
    "atlas-field-2-20": (("atlas",), "field", 2, 20),
    "atlas-field-6-34": (("atlas",), "field", 6, 34),
    "atlas-field-7-6": (("atlas",), "field", 7, 6),
    "atlas-hard-1-26": (("atlas",), "hard", 1, 26),
    "atlas-hard-2-11": (("atlas",), "hard", 2, 11),
    "atlas-hard-3-31": (("atlas",), "hard", 3, 31),
    "tuning-hard-6-57": ("tuning", "hard", 6, 57),
    "atlas-field-1-4": (("atlas",), "field", 1, 4),
    "atlas-field-1-39": (("atlas",), "field", 1, 39),
    "atlas-field-2-33": (("atlas",), "field", 2, 33),
    "atlas-field-2-6": (("atlas",), "field", 2, 6),
    "atlas-field-3-35": (("atlas",), "field", 3, 35),
}
# name: (bench/meter_cal_stress.py's case, seed, index in its stream[, its family set, when
# not the tuning families]): frame, truth and profile
STRESS = {
    "stress-mix-6-71": ("mix", 6, 71),
    "stress-mix-4-76": ("mix", 4, 76),
    "stress-long-tail-2-70": ("long-tail", 2, 70),
    "stress-long-tail-2-35": ("long-tail", 2, 35),
    "stress-long-tail-1-17": ("long-tail", 1, 17),
    "stress-setpoint-3-42": ("setpoint", 3, 42),
    "stress-wide-2-2": ("wide", 2, 2),
    "stress-setpoint-atlas-3-148": ("setpoint", 3, 148, "atlas"),
    "stress-rest-atlas-4-233": ("rest", 4, 233, "atlas"),
    "stress-long-tail-atlas-4-79": ("long-tail", 4, 79, "atlas"),
}

# name: (split, seed, lap, inspection point) of bench/meter_bench_calibrated.py's cal-ref
# row: frame, truth, reference frame ({name}-ref.png) and the calibrated profile naming it
CAL_REF = {
    "cal-ref-tuning-15-0-PG-302": ("tuning", 15, 0, "PG-302"),
    "cal-ref-tuning-29-1-PG-201": ("tuning", 29, 1, "PG-201"),
    "cal-ref-tuning-62-1-PG-201": ("tuning", 62, 1, "PG-201"),
    "cal-ref-tuning-28-0-PG-302": ("tuning", 28, 0, "PG-302"),
    "cal-ref-tuning-59-0-PG-101": ("tuning", 59, 0, "PG-101"),
    "cal-ref-tuning-24-3-PG-102": ("tuning", 24, 3, "PG-102"),
    "cal-ref-tuning-26-4-PG-201": ("tuning", 26, 4, "PG-201"),
    "cal-ref-tuning-13-1-PG-302": ("tuning", 13, 1, "PG-302"),
    "cal-ref-tuning-19-2-PG-101": ("tuning", 19, 2, "PG-101"),
    "cal-ref-tuning-13-1-PG-201": ("tuning", 13, 1, "PG-201"),
    "cal-ref-tuning-27-4-CG-301": ("tuning", 27, 4, "CG-301"),
    "cal-ref-tuning-26-1-PG-302": ("tuning", 26, 1, "PG-302"),
    "cal-ref-tuning-33-0-PG-201": ("tuning", 33, 0, "PG-201"),
    "cal-ref-tuning-24-1-PG-102": ("tuning", 24, 1, "PG-102"),
    "cal-ref-tuning-18-2-PG-201": ("tuning", 18, 2, "PG-201"),
    "cal-ref-tuning-30-4-PG-101": ("tuning", 30, 4, "PG-101"),
    "cal-ref-tuning-99-1-CG-301": ("tuning", 99, 1, "CG-301"),
    "cal-ref-tuning-99-2-CG-301": ("tuning", 99, 2, "CG-301"),
}


def render(name: str) -> tuple[np.ndarray, dict]:
    """The frame drawn from its stream (slow: every frame before it is drawn)."""
    from bench.meter_rows import ROW_IDS
    from sim_robot.gauge_scene import LEVELS, render_sample
    from sim_robot.gauge_styles import TUNING_FAMILIES

    families, level, seed, index, *row = FRAMES[name]
    if families == "tuning":
        families = TUNING_FAMILIES
    rng = np.random.default_rng([seed, ROW_IDS[row[0] if row else "tuning"], LEVELS.index(level)])
    for i in range(index + 1):
        img, truth = render_sample(families[i % len(families)], level, rng)
    return img, truth


def render_stress(name: str) -> tuple[np.ndarray, dict, dict]:
    """The stress case's frame, truth and profile drawn from its stream (slow)."""
    from bench.meter_cal_stress import FAMILY_SETS, sample, stream_rng

    case, seed, index, *fams = STRESS[name]
    family_set = fams[0] if fams else "tuning"
    rng = stream_rng(case, seed, family_set)
    for i in range(index + 1):
        img, truth, prof = sample(case, i, rng, FAMILY_SETS[family_set])
    return img, truth, prof


def render_cal_ref(name: str) -> tuple[np.ndarray, dict, np.ndarray, dict]:
    """The cal-ref frame, its truth, its point's reference frame and calibrated profile
    drawn from the row's stream (slow: every point's reference, then the laps)."""
    import tempfile

    from bench.meter_bench_calibrated import cal_ref_stream
    from sim_robot.gauge_styles import TUNING_FAMILIES

    split, seed, lap, point = CAL_REF[name]
    assert split == "tuning"  # the held-out family's frames are never stored
    with tempfile.TemporaryDirectory() as tmp:
        for k, _style, path, img, truth in cal_ref_stream(TUNING_FAMILIES, 0, seed, Path(tmp)):
            if k == lap and path.stem == point:
                prof = json.loads(path.read_text())
                ref = cv2.imread(str(Path(tmp) / prof["calibration"]["image"]), cv2.IMREAD_COLOR)
                prof["calibration"]["image"] = f"{name}-ref.png"
                return img, truth, ref, prof
    raise KeyError(name)


def read_first_drawn(family: str, level: str, seed: int):
    """The uncalibrated reading of the first frame of ``family`` at ``level`` drawn with
    ``default_rng(seed)``, and that frame's truth."""
    from app.core.meter import load_profile, read_gauge
    from sim_robot.gauge_scene import render_sample

    img, truth = render_sample(family, level, np.random.default_rng(seed))
    return read_gauge(img, load_profile(truth["profile"])), truth


def fs_off(reading, truth: dict) -> float:
    """How far a reading is from the truth, % of full scale."""
    return abs(reading.value - truth["value"]) / truth["full_scale"] * 100


def stored_cal_ref(name: str) -> tuple[np.ndarray, dict, dict]:
    """The cal-ref frame, its truth and its calibrated profile (its ``image`` relative to
    :data:`HERE`, load it with ``base_dir=HERE``) as stored."""
    img, truth = stored(name)
    return img, truth, json.loads((HERE / f"{name}.profile.json").read_text())


def read_cal_ref(name: str):
    """The stored cal-ref frame read with its calibrated profile, the reference's geometry
    measured afresh (the in-process cache emptied before and after), and its truth."""
    import app.core.meter.calibrated as calibrated
    from app.core.meter import load_profile, read_gauge

    img, truth, prof = stored_cal_ref(name)
    calibrated._REFERENCES.clear()
    try:
        return read_gauge(img, load_profile(prof, base_dir=HERE)), truth
    finally:
        calibrated._REFERENCES.clear()


def stored_stress(name: str) -> tuple[np.ndarray, dict, dict]:
    """The stress case's frame, truth and profile as stored."""
    img, truth = stored(name)
    return img, truth, json.loads((HERE / f"{name}.profile.json").read_text())


def spy_angles(monkeypatch) -> list:
    """Record every result of the angles path (:func:`app.core.meter.reader.read_by_angles`)
    while a test reads: the list the results are appended to."""
    from app.core.meter import reader as _reader

    seen = []
    rba = _reader.read_by_angles

    def spy(*a, **k):
        out = rba(*a, **k)
        seen.append(out)
        return out

    monkeypatch.setattr(_reader, "read_by_angles", spy)
    return seen


def stored(name: str) -> tuple[np.ndarray, dict]:
    """The frame and its truth as stored."""
    img = cv2.imread(str(HERE / f"{name}.png"), cv2.IMREAD_COLOR)
    if img is None:
        raise FileNotFoundError(f"{HERE / name}.png: run python -m tests.meter.stored_frames")
    truth = json.loads((HERE / f"{name}.json").read_text())
    return img, truth


def main(names=None) -> None:
    """Render and store ``names`` (all the frames when None)."""
    HERE.mkdir(exist_ok=True)
    for name in names or [*FRAMES, *STRESS, *CAL_REF]:
        if name in CAL_REF:
            img, truth, ref, prof = render_cal_ref(name)
            cv2.imwrite(str(HERE / f"{name}-ref.png"), ref, [cv2.IMWRITE_PNG_COMPRESSION, 9])
            (HERE / f"{name}.profile.json").write_text(json.dumps(prof, indent=1) + "\n")
        elif name in STRESS:
            img, truth, prof = render_stress(name)
            (HERE / f"{name}.profile.json").write_text(json.dumps(prof, indent=1) + "\n")
        else:
            img, truth = render(name)
        cv2.imwrite(str(HERE / f"{name}.png"), img, [cv2.IMWRITE_PNG_COMPRESSION, 9])
        (HERE / f"{name}.json").write_text(json.dumps(truth, indent=1, default=float) + "\n")
        print(f"{name}: {img.shape[1]}x{img.shape[0]}")


if __name__ == "__main__":
    import sys

    main(sys.argv[1:] or None)
