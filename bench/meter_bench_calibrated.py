"""Calibrated rows of the meter bench (issue 11), run from ``bench/meter_bench.py``.

* ``cal-same``: "calibrated, same image coordinates".  Field-like frames of styled gauges;
  the profile carries a calibration without an image, made from the ground-truth pivot and
  scale end marks in this frame, each coordinate moved by a uniform click error of up to
  +-3 px (``make_calibrated_profile``).
* ``cal-ref``: "calibrated with a reference frame, robot at a re-visited point".  Each of
  the station's gauges (``app/resources/station/station.json``) becomes an inspection point
  with a styled dial of its range on a fixed wall.  A reference frame at the nominal pose
  is saved as PNG next to a profile JSON in a temporary folder, with the calibration's
  clicked points (+-3 px) and ``"image"`` relative to the profile.  Then 5 laps x all
  points: new frames from slightly different poses (offset +-4 % of the frame, roll +-3
  deg, tilt +-8 deg, zoom +-8 %), new lighting, glare and value, read with
  ``read_gauge(img, load_profile(path))``.

Both rows run on the tuning families and, apart, on the held-out family (``--split``
picks one of them; ``--heldout atlas`` the former held-out family); a held-out family's
inspection points stand on its own backdrops and its frames get its own optics, as in its
uncalibrated rows (``atlas``: glare across the needle and vignetting; ``foundry``: harder
JPEG and vignetting).  Until the
reader supports calibrations (``app.core.meter.make_calibrated_profile`` and
``GaugeProfile.calibration``) they print that they are not available.
"""

from __future__ import annotations

import json
import tempfile
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

import app.core.meter as meter
from app.core.paths import resource
from bench.meter_rows import ROW_IDS, WRONG_PCT_FS, Tally, heldout_opt, print_row, timed_read
from sim_robot.gauge_atlas import ATLAS
from sim_robot.gauge_foundry import FOUNDRY
from sim_robot.gauge_scene import Look, Pose, background, compose, own_backdrops, render_sample
from sim_robot.gauge_styles import (
    HELD_OUT_CHOICES,
    HELD_OUT_FAMILY,
    TUNING_FAMILIES,
    random_style,
    random_value,
)

CLICK_PX = 3.0
LAPS = 5
NOT_AVAILABLE = "calibrated reader not available (profile has no calibration support)"


def calibration_support() -> str | None:
    """None when the reader reads calibrated profiles, else why not."""
    fields = getattr(meter.GaugeProfile, "__dataclass_fields__", {})
    if not hasattr(meter, "make_calibrated_profile") or "calibration" not in fields:
        return NOT_AVAILABLE
    return None


def _clicked(p, rng) -> list[float]:
    return [float(v + rng.uniform(-CLICK_PX, CLICK_PX)) for v in p]


def calibrated_profile(truth: dict, rng, image: str | None = None) -> dict:
    """The profile an operator would make by clicking pivot and end marks in ``truth``'s
    frame (with click noise); keeps the face's needle and set-point hints."""
    prof = truth["profile"]
    base = {k: v for k, v in prof.items() if k not in ("min_angle_deg", "max_angle_deg")}
    clockwise = prof["max_angle_deg"] > prof["min_angle_deg"]
    d = meter.make_calibrated_profile(
        base, _clicked(truth["pivot_xy"], rng), _clicked(truth["min_mark_xy"], rng),
        _clicked(truth["max_mark_xy"], rng), image=image, clockwise=clockwise)
    for k in ("needle", "ignore_colour"):
        if k in prof:
            d.setdefault(k, prof[k])
    return d


def _dump(dump: Path, stem: str, img, truth: dict, prof: dict, r) -> None:
    """A refused or wrong frame with its truth, its calibrated profile and the reading."""
    dump.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(dump / f"{stem}.png"), img)
    out = dict(truth, calibrated_profile=prof,
               reading={"value": r.value, "confidence": r.confidence, "error": r.error,
                        "scores": r.scores})
    (dump / f"{stem}.json").write_text(json.dumps(out, indent=1, default=float))


def run_cal_same(families, split_id: int, n: int, seed: int, dump: Path | None = None) -> Tally:
    """``n`` field frames read with click-noisy calibrations; with ``dump``, the refused and
    wrong ones are written there (PNG and JSON)."""
    rng = np.random.default_rng([seed, ROW_IDS["cal-same"], split_id])
    tally = Tally()
    for i in range(n):
        img, truth = render_sample(families[i % len(families)], "field", rng)
        d = calibrated_profile(truth, rng)
        r, ms = timed_read(img, meter.load_profile(d))
        tally.add(r, truth["value"], truth["full_scale"], ms, f"cal-same #{i} {truth['style']}")
        wrong = r.value is not None and (abs(r.value - truth["value"]) / truth["full_scale"]
                                         * 100 > WRONG_PCT_FS)
        if dump is not None and (r.value is None or wrong):
            _dump(dump, f"cal-same-{i:04d}", img, truth, d, r)
    return tally


def station_points() -> list[dict]:
    d = json.loads(resource("station", "station.json").read_text())
    return d["gauges"]


def _look(rng, family: str = "") -> Look:
    look = Look(light=float(rng.uniform(0, 0.3)), light_angle_deg=float(rng.uniform(0, 360)),
                glare=float(rng.uniform(0.0, 0.5)), streaks=int(rng.integers(0, 2)),
                lens_k=0.03, noise_sigma=float(rng.uniform(1, 4)),
                blur_px=float(rng.uniform(0, 0.7)), jpeg_quality=int(rng.integers(70, 95)))
    if family == ATLAS:  # its own optics: glare across the needle, vignetting
        look = replace(look, streak_on_needle=bool(rng.random() < 0.35),
                       vignette=float(rng.uniform(0.1, 0.35)))
    elif family == FOUNDRY:  # photographs: harder JPEG, vignetting
        look = replace(look, jpeg_quality=int(rng.integers(45, 85)),
                       vignette=float(rng.uniform(0.05, 0.25)))
    return look


def cal_ref_stream(families, split_id: int, seed: int, folder: Path):
    """The ``cal-ref`` row's frames: reference frames and profiles for every point written
    to ``folder``, then the laps, yielding (lap, style, profile path, frame, truth)."""
    rng = np.random.default_rng([seed, ROW_IDS["cal-ref"], split_id])
    w, h = 640, 480
    points = []
    for k, g in enumerate(station_points()):
        style = random_style(families[k % len(families)], rng,
                             value_range=(float(g["min"]), float(g["max"]), g["unit"]),
                             name=g["id"])
        kinds = (list(own_backdrops(style.family)) if style.family in HELD_OUT_CHOICES
                 else ["wall", "pipes", "gauges"])
        wall = background(rng, 2 * w, 2 * h, str(rng.choice(kinds)), style.family)
        nominal = Pose(fill=float(rng.uniform(0.45, 0.6)),
                       offset=tuple(rng.uniform(-0.1, 0.1, 2)),
                       tilt_deg=float(rng.uniform(0, 15)),
                       tilt_axis_deg=float(rng.uniform(0, 180)),
                       roll_deg=float(rng.uniform(-3, 3)))
        img, truth = compose(style, random_value(style, rng), rng, frame_size=(w, h),
                             pose=nominal, look=_look(rng, style.family), backdrop=wall)
        ref = folder / "ref" / f"{g['id']}.png"
        ref.parent.mkdir(parents=True, exist_ok=True)
        cv2.imwrite(str(ref), img)
        path = folder / f"{g['id']}.json"
        path.write_text(json.dumps(calibrated_profile(truth, rng, image=f"ref/{ref.name}"),
                                   indent=2))
        points.append((style, wall, nominal, path))
    for lap in range(LAPS):
        for style, wall, nominal, path in points:
            pose = Pose(fill=nominal.fill,
                        offset=tuple(np.array(nominal.offset) + rng.uniform(-0.04, 0.04, 2)),
                        tilt_deg=abs(nominal.tilt_deg + float(rng.uniform(-8, 8))),
                        tilt_axis_deg=nominal.tilt_axis_deg,
                        roll_deg=nominal.roll_deg + float(rng.uniform(-3, 3)),
                        zoom=float(rng.uniform(0.92, 1.08)))
            value = random_value(style, rng)
            img, truth = compose(style, value, rng, frame_size=(w, h), pose=pose,
                                 look=_look(rng, style.family), backdrop=wall)
            yield lap, style, path, img, truth


def run_cal_ref(families, split_id: int, seed: int, folder: Path,
                dump: Path | None = None) -> Tally:
    """Reference frames and profiles for every point in ``folder``, then the laps; with
    ``dump``, the refused and wrong frames are written there with their reference frame."""
    tally = Tally()
    for lap, style, path, img, truth in cal_ref_stream(families, split_id, seed, folder):
        try:
            prof = meter.load_profile(path)
        except ValueError as e:  # a bad profile is a refusal of every frame, counted
            tally.n += 1
            tally.reasons[str(e)] = tally.reasons.get(str(e), 0) + 1
            continue
        r, ms = timed_read(img, prof)
        tally.add(r, truth["value"], truth["full_scale"], ms,
                  f"cal-ref lap {lap} {style.name} ({style.family})")
        wrong = r.value is not None and (abs(r.value - truth["value"])
                                         / truth["full_scale"] * 100 > WRONG_PCT_FS)
        if dump is not None and (r.value is None or wrong):
            stem = f"cal-ref-{lap}-{path.stem}"
            _dump(dump, stem, img, truth, json.loads(path.read_text()), r)
            ref = cv2.imread(str(folder / "ref" / f"{path.stem}.png"))
            cv2.imwrite(str(dump / f"{stem}-ref.png"), ref)
    return tally


def calibrated_rows(args) -> None:
    tuning = tuple(args.family.split(",")) if args.family else TUNING_FAMILIES
    fam_opt = f" --family {args.family}" if args.family else ""
    held = getattr(args, "heldout", HELD_OUT_FAMILY)
    splits = [sp for sp in (("tuning", tuning, 0, fam_opt), ("held-out", (held,), 1,
                                                              heldout_opt(held)))
              if getattr(args, "split", "both") in ("both", sp[0].replace("-", ""))]
    why = calibration_support()
    for row in ("cal-same", "cal-ref"):
        if row not in args.rows:
            continue
        for split, fams, sid, opt in splits:
            label = f"{row} {split}"
            if why:
                print(f"{label:22} {why}")
                continue
            if row == "cal-same":
                # the held-out family's failures are not for looking at: never dumped
                dump = Path(args.dump) if args.dump and split == "tuning" else None
                tally = run_cal_same(fams, sid, args.n, args.seed, dump)
                cmd = f"python bench/meter_bench.py --rows cal-same --n {args.n} --seed {args.seed}"
            else:
                dump = Path(args.dump) if args.dump and split == "tuning" else None
                with tempfile.TemporaryDirectory(prefix="meter-cal-ref-") as tmp:
                    tally = run_cal_ref(fams, sid, args.seed, Path(tmp), dump)
                cmd = f"python bench/meter_bench.py --rows cal-ref --seed {args.seed}"
            print_row(label, tally, row, cmd + opt + f" --split {split.replace('-', '')}",
                      args.verbose)
