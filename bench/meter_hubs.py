"""Where the uncalibrated reader's pivot comes from, and how far it lies from the truth.

    python bench/meter_hubs.py [--seeds 1,2] [--n 40] [--root CHECKOUT]

Reads the images of ``bench/meter_bench.py --rows tuning`` (the same generator and random
streams, one set per seed; the tuning families only) with the reader of ``--root`` (by
default this checkout; another checkout, e.g. an older commit, to compare) and counts, per
level, how the pointer's hub was found on the first look at the dial
(``pointer.read_normalised``'s first call per image):

* ``region``: a circle fits the boundary of the pointer's region about its thickest point
  (seed 000 section 3.2);
* ``edges``: a circle fits the grey image's edges about the needle's line
  (:mod:`app.core.meter.hub_edges`; a reader without it never says so);
* ``base``: neither, the hub is the region's thickest point near the centre;
* ``none``: no hub (no pointer found).

It also prints, over the readings returned, the mean and largest distance in image pixels
from the reading's pivot (``Reading.dial_centre_xy``) to the true pivot, and readable %,
MAE and wrong readings (> 2 % FS) as the bench counts them.
"""

from __future__ import annotations

import argparse
import importlib
import math
import pkgutil
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", default="1")
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--levels", default="clean,field,hard")
    ap.add_argument("--root", default=str(ROOT), help="checkout whose reader is measured")
    a = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    sys.path.insert(0, str(Path(a.root).resolve()))
    import cv2

    import app.core.meter as meter
    from app.core.meter import load_profile, pointer, read_gauge
    from bench.meter_rows import ROW_IDS, WRONG_PCT_FS
    from sim_robot.gauge_scene import LEVELS, render_sample
    from sim_robot.gauge_styles import TUNING_FAMILIES

    cv2.setNumThreads(1)
    seen: list[dict] = []
    orig = pointer.read_normalised

    def wrapped(img, prof):
        res = orig(img, prof)
        seen.append(res)
        return res

    for mod in pkgutil.iter_modules(meter.__path__):
        if mod.name != "__main__":
            m = importlib.import_module("app.core.meter." + mod.name)
            if getattr(m, "read_normalised", None) is orig:
                m.read_normalised = wrapped
    print(f"meter hubs: tuning rows, n={a.n} per level, seeds {a.seeds}; reader in {a.root}")
    for level in a.levels.split(","):
        kinds = {"region": 0, "edges": 0, "base": 0, "none": 0}
        errs, dists, wrong, n = [], [], 0, 0
        for seed in (int(s) for s in a.seeds.split(",")):
            rng = np.random.default_rng([seed, ROW_IDS["tuning"], LEVELS.index(level)])
            for i in range(a.n):
                img, truth = render_sample(TUNING_FAMILIES[i % len(TUNING_FAMILIES)], level,
                                           rng)
                seen.clear()
                r = read_gauge(img, load_profile(truth["profile"]))
                n += 1
                first = seen[0] if seen else {}
                if "hub_rms" not in first:
                    kinds["none"] += 1
                else:
                    kinds[first.get("hub_from",
                                    "region" if first["hub_rms"] < 1.5 else "base")] += 1
                if r.value is None:
                    continue
                e = abs(r.value - truth["value"]) / truth["full_scale"] * 100.0
                errs.append(e)
                wrong += e > WRONG_PCT_FS
                if r.dial_centre_xy is not None:
                    dists.append(math.dist(r.dial_centre_xy, truth["pivot_xy"]))
        share = ", ".join(f"{k} {v}" for k, v in kinds.items())
        mae = float(np.mean(errs)) if errs else float("nan")
        dd = f"{np.mean(dists):.2f} px (largest {np.max(dists):.1f})" if dists else "-"
        print(f"{level:6s} hub on the first look: {share} (of {n}); readable "
              f"{100.0 * len(errs) / max(n, 1):.1f} % MAE {mae:.4f} wrong {wrong}; "
              f"pivot to truth {dd}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
