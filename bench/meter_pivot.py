"""How far the profile-angles path's pivot lies from the true pivot, on the tuning rows.

    python bench/meter_pivot.py [--n 40] [--seed 3] [--levels clean,field,hard] [-v]

Renders the same images as ``meter_bench.py --rows tuning`` (same seed, same order) and
reads each with ``read_gauge``; for every image that reaches the profile-angles path it
takes the centre that path unwrapped the polar image about (the last call of
:func:`app.core.meter.angles.read_by_angles` of that reading, in the normalised crop) and
the generator's true pivot carried into the same crop (through the reader's own
image -> crop homography).  The bench compares with the truth; the reader never sees it.

Per level it prints the error (crop px; the face's radius is 135 px; median / p90 / max)
of the scale ring's circle centre (:func:`~app.core.meter.angles.ring_centre`), of the
centre the reading used, of the comb's centre (:mod:`app.core.meter.comb_centre`, started
from the ring's, where it is found, beside the ring's on the same images) and of the
hub; and for the ring's centre its mean component toward the scale's gap (positive:
toward the gap, which turns both end marks inward), also over the readings refused with
the end marks off the profile's span.  ``-v`` lists every image: the errors, and how
much the ring's centre changes the end marks' span against the true pivot (deg).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from app.core.meter import load_profile  # noqa: E402
from app.core.meter import reader as _reader  # noqa: E402
from app.core.meter import ring_centre as _ring  # noqa: E402
from app.core.meter.comb_centre import comb_centre  # noqa: E402
from app.core.meter.dial import FACE_RADIUS  # noqa: E402
from bench import meter_rows  # noqa: E402
from sim_robot.gauge_scene import LEVELS, render_sample  # noqa: E402
from sim_robot.gauge_styles import TUNING_FAMILIES  # noqa: E402


class _Probe:
    """Wraps the reader's angles steps to note the crop homography and the centres."""

    def __init__(self):
        self.calls: list = []
        self._full = None
        self._ar, self._rba = _reader._angles_reading, _reader.read_by_angles

        def angles_reading(res, crop, full, *a, **k):
            self._full = full
            return self._ar(res, crop, full, *a, **k)

        def read_by_angles(res, prof, crop, kp=None):
            out = self._rba(res, prof, crop, kp)
            if "centre" in out and self._full is not None:
                hid = _ring.hidden_float(_ring.needle_only(res["pmask"], res["line"]))
                comb = comb_centre(res["dark"].astype(np.float32), res["otsu_t"],
                                   out["ring_centre"], FACE_RADIUS, hid)
                self.calls.append((self._full, out["ring_centre"], out["centre"], comb,
                                   res["centre"]))
            return out

        _reader._angles_reading = angles_reading
        _reader.read_by_angles = read_by_angles


def _gap_dir(prof) -> np.ndarray:
    """Unit vector (image axes, y down) from the pivot toward the middle of the scale's gap
    on the upright dial."""
    a = min(prof.min_angle_deg, prof.max_angle_deg) + prof.span_deg + \
        (360.0 - prof.span_deg) / 2.0
    return np.array([math.sin(math.radians(a)), -math.cos(math.radians(a))])


def _span(prof, centre, ends) -> float:
    """The arc from the minimum end mark to the maximum one about ``centre`` (deg, the
    scale's sense)."""
    a = [math.degrees(math.atan2(e[0] - centre[0], -(e[1] - centre[1]))) for e in ends]
    sign = 1.0 if prof.clockwise else -1.0
    return (sign * (a[1] - a[0])) % 360.0


def _stats(e) -> str:
    e = np.asarray(e)
    return (f"n={len(e):3d} median {np.median(e):5.2f} p90 {np.percentile(e, 90):5.2f} "
            f"max {e.max():6.2f}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--levels", default="clean,field,hard")
    ap.add_argument("-v", "--verbose", action="store_true")
    args = ap.parse_args(argv)
    cv2.setNumThreads(1)
    probe = _Probe()
    for level in args.levels.split(","):
        rng = np.random.default_rng([args.seed, meter_rows.ROW_IDS["tuning"],
                                     LEVELS.index(level)])
        ring, used, hub, comb, comb_ring, gaps, off, off_gaps = ([] for _ in range(8))
        for i in range(args.n):
            fam = TUNING_FAMILIES[i % len(TUNING_FAMILIES)]
            img, truth = render_sample(fam, level, rng)
            prof = load_profile(truth["profile"])
            probe.calls.clear()
            r, _ = meter_rows.timed_read(img, prof)
            if not probe.calls:
                continue
            full, c_ring, c_used, c_comb, c_hub = probe.calls[-1]

            def crop_xy(xy, full=full):
                v = full @ np.array([*xy, 1.0])
                return v[:2] / v[2]

            piv = crop_xy(truth["pivot_xy"])
            ends = [crop_xy(truth[k]) for k in ("min_mark_xy", "max_mark_xy")]
            d = np.array(c_ring) - piv
            e_ring, gap = float(np.hypot(*d)), float(d @ _gap_dir(prof))
            ring.append(e_ring)
            gaps.append(gap)
            used.append(float(np.hypot(*(np.array(c_used) - piv))))
            hub.append(float(np.hypot(*(np.array(c_hub) - piv))))
            txt = "comb    -             "
            if c_comb is not None:
                comb.append(float(np.hypot(*(np.array(c_comb[0]) - piv))))
                comb_ring.append(e_ring)
                txt = f"comb {comb[-1]:5.2f} (se {c_comb[1]:4.2f})"
            if r.value is None and "off the profile's span" in (r.error or ""):
                off.append(e_ring)
                off_gaps.append(gap)
            if args.verbose:
                what = f"{r.value:.4g}" if r.value is not None else (r.error or "?")[-60:]
                d_span = _span(prof, np.array(c_ring), ends) - _span(prof, piv, ends)
                print(f"  {level} #{i:02d} {truth['style']:22} ring {e_ring:5.2f} "
                      f"(toward gap {gap:+5.2f}, span {d_span:+5.2f}"
                      f" deg) used {used[-1]:5.2f} {txt}  {what}")
        if not ring:
            continue
        print(f"{level:6} ring centre {_stats(ring)} px, toward the gap {np.mean(gaps):+5.2f}")
        if off:
            print(f"{level:6}   refused, ends off span: ring centre {_stats(off)} px, toward "
                  f"the gap {np.mean(off_gaps):+5.2f}")
        print(f"{level:6} centre used {_stats(used)} px")
        if comb:
            print(f"{level:6} comb centre {_stats(comb)} px; the ring's on the same images "
                  f"{_stats(comb_ring)}")
        print(f"{level:6} hub         {_stats(hub)} px")
    return 0


if __name__ == "__main__":
    sys.exit(main())
