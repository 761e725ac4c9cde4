"""Two versions of the gauge reader on the same images, read alternately: CPU and readings.

    python bench/meter_ab.py --old /path/to/old/checkout [--new .] [--n 40] [--seed 3]

The uncalibrated tuning rows of ``bench/meter_bench.py`` (the same images: the same
generator and random streams as ``--rows tuning``) are rendered once; each version reads
them in its own worker process (its own checkout on ``PYTHONPATH``, OpenCV on one
thread), image by image in turn, the order flipped every image, so that a busy machine
weighs on both alike.  Each worker first imports every module of the reader and loads the
keypoint model (one-time costs a reading would otherwise carry on first use) and reads one
image unmeasured.  Printed per level: the mean CPU ms per image of each version
(``time.process_time`` around ``read_gauge`` in the worker), readable %, MAE and wrong
readings of each, and then every image whose reading (value, confidence or refusal
text) differs.  Only the tuning families are read (or, with ``--families``, some of them
or a former held-out family, as ``bench/meter_why.py`` reads): the held-out family is never
looked at here.
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.meter_rows import ROW_IDS, WRONG_PCT_FS  # noqa: E402
from sim_robot.gauge_scene import LEVELS, render_sample  # noqa: E402
from sim_robot.gauge_styles import HELD_OUT_CHOICES, HELD_OUT_FAMILY, TUNING_FAMILIES  # noqa: E402

# families it may read: the tuning ones, and former held-out ones; never the held-out family
FAMILIES = (*TUNING_FAMILIES, *(f for f in HELD_OUT_CHOICES if f != HELD_OUT_FAMILY))

# the worker runs in the other checkout too, so it is a string, not this file's code
WORKER = """
import json, pickle, sys, time
import cv2
cv2.setNumThreads(1)
import importlib, pkgutil
import app.core.meter
from app.core.meter import load_profile, read_gauge
items = [(img, load_profile(prof)) for img, prof in pickle.load(open(sys.argv[1], "rb"))]
# warm-up: the modules a reading imports on first use (compiled from source when no
# bytecode is written) and the keypoint model, once per process, then one reading
for mod in pkgutil.iter_modules(app.core.meter.__path__):
    if mod.name != "__main__":
        importlib.import_module("app.core.meter." + mod.name)
try:
    from app.core.meter.keypoints import load_model
    load_model()
except ImportError:
    pass
read_gauge(*items[0])
print("ready", flush=True)
for line in sys.stdin:
    img, prof = items[int(line)]
    c0 = time.process_time()
    r = read_gauge(img, prof)
    ms = (time.process_time() - c0) * 1000.0
    print(json.dumps({"v": r.value, "c": r.confidence, "e": r.error, "ms": ms}), flush=True)
"""


def render(n: int, seed: int, levels: list[str], families: tuple[str, ...] = TUNING_FAMILIES
           ) -> list[tuple[str, int, np.ndarray, dict]]:
    """The tuning row's images (as ``meter_rows.run_uncalibrated`` draws them), of
    ``families`` in turn."""
    out = []
    for level in levels:
        rng = np.random.default_rng([seed, ROW_IDS["tuning"], LEVELS.index(level)])
        for i in range(n):
            img, truth = render_sample(families[i % len(families)], level, rng)
            out.append((level, i, img, truth))
    return out


class Worker:
    def __init__(self, root: Path, images: str):
        env = dict(os.environ, PYTHONPATH=str(root))
        self.p = subprocess.Popen([sys.executable, "-c", WORKER, images], cwd=root, env=env,
                                  stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        if self.p.stdout.readline().strip() != "ready":
            raise RuntimeError(f"the reader in {root} did not start")

    def read(self, k: int) -> dict:
        self.p.stdin.write(f"{k}\n")
        self.p.stdin.flush()
        return json.loads(self.p.stdout.readline())

    def close(self) -> None:
        self.p.stdin.close()
        self.p.wait()


def summary(cases, rs, level: str) -> str:
    errs, wrong, n = [], 0, 0
    for (lv, _, _, truth), r in zip(cases, rs, strict=True):
        if lv != level:
            continue
        n += 1
        if r["v"] is not None:
            e = abs(r["v"] - truth["value"]) / truth["full_scale"] * 100.0
            errs.append(e)
            wrong += e > WRONG_PCT_FS
    mae = float(np.mean(errs)) if errs else float("nan")
    return f"readable {100.0 * len(errs) / max(n, 1):5.1f} % MAE {mae:.4f} wrong {wrong}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--old", required=True, help="checkout of the version to compare with")
    ap.add_argument("--new", default=str(ROOT), help="checkout of the new version (this one)")
    ap.add_argument("--n", type=int, default=40, help="images per level")
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--levels", default="clean,field,hard")
    ap.add_argument("--families", default=",".join(TUNING_FAMILIES),
                    help=f"families to read in turn, of {', '.join(FAMILIES)}")
    args = ap.parse_args(argv)
    levels = args.levels.split(",")
    if any(lv not in LEVELS for lv in levels):
        ap.error(f"levels are {', '.join(LEVELS)}")
    families = tuple(args.families.split(","))
    if any(f not in FAMILIES for f in families):
        ap.error(f"families are {', '.join(FAMILIES)} (the held-out family is not read here)")
    cases = render(args.n, args.seed, levels, families)
    with tempfile.TemporaryDirectory() as tmp:
        images = str(Path(tmp) / "images.pkl")
        with open(images, "wb") as f:
            pickle.dump([(img, truth["profile"]) for _, _, img, truth in cases], f)
        workers = {"old": Worker(Path(args.old).resolve(), images),
                   "new": Worker(Path(args.new).resolve(), images)}
        res: dict = {"old": [], "new": []}
        for k in range(len(cases)):
            for who in (("old", "new") if k % 2 == 0 else ("new", "old")):
                res[who].append(workers[who].read(k))
        for w in workers.values():
            w.close()
    fams = "tuning" if families == TUNING_FAMILIES else ",".join(families)
    print(f"meter A/B: {fams} rows, n={args.n} per level, seed={args.seed}; old {args.old}, "
          f"new {args.new}; load average {os.getloadavg()[0]:.1f}")
    for level in levels:
        ms = {who: np.mean([r["ms"] for (lv, *_), r in zip(cases, res[who], strict=True)
                            if lv == level]) for who in res}
        print(f"{level:6} cpu ms old {ms['old']:6.1f} new {ms['new']:6.1f} "
              f"({100.0 * (ms['new'] / ms['old'] - 1.0):+.0f} %)   old "
              f"{summary(cases, res['old'], level)} | new {summary(cases, res['new'], level)}")
    def err(r: dict, truth: dict) -> str:
        if r["v"] is None:
            return "-"
        return f"{abs(r['v'] - truth['value']) / truth['full_scale'] * 100.0:.3f}"

    diff = 0
    for k, (a, b) in enumerate(zip(res["old"], res["new"], strict=True)):
        if (a["v"], a["c"], a["e"]) != (b["v"], b["c"], b["e"]):
            diff += 1
            print(f"  differs: {cases[k][0]} #{cases[k][1]} (% FS off: {err(a, cases[k][3])} -> "
                  f"{err(b, cases[k][3])}): old {a['v']} ({a['c']}) "
                  f"{a['e'] or ''} | new {b['v']} ({b['c']}) {b['e'] or ''}")
    print(f"{diff} of {len(cases)} readings differ (value, confidence or refusal text)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
