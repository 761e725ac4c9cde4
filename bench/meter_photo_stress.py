"""The uncalibrated reader on the tuning rows' images made worse as a camera makes them:
readable, MAE and wrong readings by condition and level.

    python bench/meter_photo_stress.py [--conditions none,noise8,...] [--seeds 3,4] [--n 40]
        [--calibrated]

Each image of ``bench/meter_bench.py --rows tuning`` (the same generator and random
streams; the tuning families only, never the held-out one) is read as rendered and after
each condition laid on top of it:

- ``noiseS``: white Gaussian noise of σ S grey levels per channel (a dark scene's gain);
- ``jpegQ``: JPEG at quality Q;
- ``mblurN``: motion blur N px long at a random angle (a shaking mast);
- ``half``: the image at half its size (a gauge twice as far);
- ``bigN``: the image N times larger (bicubic; a phone's photograph of a dial close up);
- ``wideN``: the image in the middle of a frame N times as wide and high, the rest its
  median colour (a dial photographed from N times farther; a crop so placed is still
  square, and read as a crop);
- ``dark``: gamma 1.8 (an under-exposed frame);
- ``photo``: motion blur 4 px, noise σ 5 and JPEG 40 together;
- ``a+b``: the conditions in turn (``big4+wide3``: a dial photographed at a phone's
  resolution from three times as far).

With ``--calibrated`` the frames are those of ``--rows cal-same`` (field frames of the
tuning families, each read through a profile calibrated by clicks with click noise),
``--n`` per seed, shown in the ``field`` column.

The condition's random draws come from the seed, the image's index and its level, so two
checkouts see the same images (run this script from each for an A/B).  Printed per
condition and level: readable %, wrong (returned and > 2 % FS off), MAE % FS and CPU ms of
``read_gauge``; then each condition's refusals by deciding reason and its wrong readings.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from app.core.meter import load_profile, read_gauge  # noqa: E402
from bench.meter_bench_calibrated import calibrated_profile  # noqa: E402
from bench.meter_rows import ROW_IDS, WRONG_PCT_FS, deciding_reason  # noqa: E402
from sim_robot.gauge_scene import LEVELS, render_sample  # noqa: E402
from sim_robot.gauge_styles import TUNING_FAMILIES  # noqa: E402


def _jpeg(img, q):
    _, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, int(q)])
    return cv2.imdecode(buf, cv2.IMREAD_UNCHANGED)


def _noise(img, sigma, rng):
    return np.clip(img.astype(np.float32) + rng.normal(0, sigma, img.shape), 0,
                   255).astype(np.uint8)


def _motion(img, n, angle_deg):
    k = np.zeros((n, n), np.float32)
    k[n // 2, :] = 1.0
    m = cv2.getRotationMatrix2D((n / 2 - 0.5, n / 2 - 0.5), angle_deg, 1.0)
    k = cv2.warpAffine(k, m, (n, n))
    return cv2.filter2D(img, -1, k / k.sum())


def condition(name: str, img: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """``img`` made worse by the condition ``name`` (see the module's list; ``a+b`` lays
    ``a`` then ``b``)."""
    if "+" in name:
        for part in name.split("+"):
            img = condition(part, img, rng)
        return img
    if name == "none":
        return img
    if m := re.fullmatch(r"noise(\d+(?:\.\d+)?)", name):
        return _noise(img, float(m[1]), rng)
    if m := re.fullmatch(r"jpeg(\d+)", name):
        return _jpeg(img, int(m[1]))
    if m := re.fullmatch(r"mblur(\d+)", name):
        return _motion(img, int(m[1]), rng.uniform(0, 180))
    if m := re.fullmatch(r"big(\d+)", name):
        return cv2.resize(img, None, fx=int(m[1]), fy=int(m[1]), interpolation=cv2.INTER_CUBIC)
    if m := re.fullmatch(r"wide(\d+)", name):
        h, w = img.shape[:2]
        dy, dx = (int(m[1]) - 1) * h // 2, (int(m[1]) - 1) * w // 2
        fill = [int(v) for v in np.median(img.reshape(-1, img.shape[2]), axis=0)]
        return cv2.copyMakeBorder(img, dy, dy, dx, dx, cv2.BORDER_CONSTANT, value=fill)
    if name == "half":
        h, w = img.shape[:2]
        return cv2.resize(img, (w // 2, h // 2), interpolation=cv2.INTER_AREA)
    if name == "dark":
        return cv2.LUT(img, (255 * (np.arange(256) / 255) ** 1.8).astype(np.uint8))
    if name == "photo":
        return _jpeg(_noise(_motion(img, 4, rng.uniform(0, 180)), 5, rng), 40)
    raise ValueError(f"unknown condition {name!r}")


def _frames(seed: int, li: int, level: str, n: int, calibrated: bool):
    """``(index, image, truth, profile)`` of the tuning row (or the cal-same row)."""
    if calibrated:
        rng = np.random.default_rng([seed, ROW_IDS["cal-same"], 0])  # as run_cal_same
    else:
        rng = np.random.default_rng([seed, ROW_IDS["tuning"], li])
    for i in range(n):
        img, truth = render_sample(TUNING_FAMILIES[i % len(TUNING_FAMILIES)], level, rng)
        prof = load_profile(calibrated_profile(truth, rng) if calibrated else truth["profile"])
        yield i, img, truth, prof


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--conditions", default="none,noise6,noise8,noise12,jpeg30,mblur5,half,"
                    "dark,photo")
    ap.add_argument("--seeds", default="3,4")
    ap.add_argument("--n", type=int, default=40, help="images per level and seed")
    ap.add_argument("--calibrated", action="store_true",
                    help="the cal-same row's frames, read through their clicked calibrations")
    args = ap.parse_args(argv)
    conds = args.conditions.split(",")
    try:
        for c in conds:
            condition(c, np.zeros((4, 4, 3), np.uint8), np.random.default_rng(0))
    except ValueError as e:
        ap.error(str(e))
    cv2.setNumThreads(1)
    recs: dict[tuple[str, str], list] = {}
    for seed in (int(s) for s in args.seeds.split(",")):
        for li, level in enumerate(LEVELS):
            if args.calibrated and level != "field":
                continue
            for i, img, truth, prof in _frames(seed, li, level, args.n, args.calibrated):
                for c in conds:
                    im = condition(c, img, np.random.default_rng([seed, i, li, 7]))
                    t = time.process_time()
                    r = read_gauge(im, prof)
                    dt = time.process_time() - t
                    err = None if r.value is None else \
                        abs(r.value - truth["value"]) / truth["full_scale"] * 100.0
                    why = None if r.value is not None else \
                        re.sub(r"[-+]?\d+(\.\d+)?", "#", deciding_reason(r.error))
                    recs.setdefault((c, level), []).append(
                        (err, why, dt, f"seed {seed} {level} #{i} {truth['style']}"))
    levels = ("field",) if args.calibrated else LEVELS
    print(f"meter photo stress{' (calibrated, cal-same frames)' if args.calibrated else ''}: "
          f"tuning families, seeds {args.seeds}, n={args.n} per level and "
          "seed; readable %, wrong (> 2 % FS), MAE % FS, CPU ms")
    for c in conds:
        cells = []
        for level in levels:
            rr = recs[(c, level)]
            errs = [x[0] for x in rr if x[0] is not None]
            wrong = sum(e > WRONG_PCT_FS for e in errs)
            mae = float(np.mean(errs)) if errs else float("nan")
            cells.append(f"{level} {100.0 * len(errs) / len(rr):5.1f} % w{wrong} "
                         f"{mae:.3f} {1000 * np.mean([x[2] for x in rr]):5.1f} ms")
        print(f"{c:8s} " + "  ".join(cells))
    for c in conds:
        whys: dict[str, int] = {}
        wrongs = []
        for level in levels:
            for err, why, _, name in recs[(c, level)]:
                if why is not None:
                    whys[why] = whys.get(why, 0) + 1
                elif err > WRONG_PCT_FS:
                    wrongs.append(f"{name} {err:.2f} % FS")
        print(f"\n{c}: refusals by deciding reason")
        for why, k in sorted(whys.items(), key=lambda kv: -kv[1]):
            print(f"  {k:4d}  {why}")
        for w in wrongs:
            print(f"  WRONG {w}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
