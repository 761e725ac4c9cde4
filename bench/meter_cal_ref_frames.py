"""The ``cal-ref`` row's readings frame by frame, over many seeds, and two runs compared.

    python bench/meter_cal_ref_frames.py --seeds 11-40 --out after.json
    python bench/meter_cal_ref_frames.py --compare before.json after.json

The frames are those of ``bench/meter_bench.py --rows cal-ref --split tuning --n 300
--seed S`` (``bench.meter_bench_calibrated.cal_ref_stream``, tuning families only: the
held-out family is never read here), read by ``read_gauge``.  Each frame's record: seed,
lap, point, family, value, truth, error in % FS, confidence, refusal and scores.  Run it
from the checkout to be measured (``PYTHONPATH=<checkout>``).  ``--compare`` prints, per
block of 30 seeds, readable / wrong (> 2 % FS) / MAE of each run, then every frame whose
value or refusal differs.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from app.core.meter import load_profile  # noqa: E402
from bench.meter_bench_calibrated import cal_ref_stream  # noqa: E402
from bench.meter_rows import WRONG_PCT_FS, timed_read  # noqa: E402
from sim_robot.gauge_styles import TUNING_FAMILIES  # noqa: E402


def scan(first: int, last: int) -> list[dict]:
    rows = []
    for seed in range(first, last + 1):
        with tempfile.TemporaryDirectory(prefix="meter-cal-ref-") as tmp:
            for lap, style, path, img, truth in cal_ref_stream(TUNING_FAMILIES, 0, seed,
                                                               Path(tmp)):
                r, ms = timed_read(img, load_profile(path))
                err = None if r.value is None else \
                    abs(r.value - truth["value"]) / truth["full_scale"] * 100
                rows.append(dict(seed=seed, lap=lap, point=path.stem, family=style.family,
                                 value=r.value, truth=truth["value"], err=err,
                                 conf=r.confidence, error=r.error,
                                 scores=getattr(r, "scores", {}), cpu_ms=ms))
        print(seed, sum(x["value"] is not None for x in rows if x["seed"] == seed),
              flush=True)
    return rows


def _summary(rows: list[dict]) -> str:
    ok = [x for x in rows if x["value"] is not None]
    wrong = [x for x in ok if x["err"] > WRONG_PCT_FS]
    mae = sum(x["err"] for x in ok) / max(len(ok), 1)
    return (f"{len(ok)}/{len(rows)} readable, wrong {len(wrong)} "
            f"{[(x['seed'], x['lap'], x['point']) for x in wrong]}, MAE {mae:.3f} % FS")


def compare(a_path: str, b_path: str) -> None:
    runs = [json.loads(Path(p).read_text()) for p in (a_path, b_path)]
    seeds = sorted({x["seed"] for x in runs[0]})
    for lo in range(seeds[0], seeds[-1] + 1, 30):
        for name, rows in zip((a_path, b_path), runs, strict=True):
            block = [x for x in rows if lo <= x["seed"] < lo + 30]
            print(f"seeds {lo}-{min(lo + 29, seeds[-1])} {name}: {_summary(block)}")
    a, b = ({(x["seed"], x["lap"], x["point"]): x for x in rows} for rows in runs)
    same = 0
    for k in sorted(a):
        x, y = a[k], b.get(k)
        if y is not None and x["value"] == y["value"] and x["error"] == y["error"]:
            same += 1
            continue

        def show(z):
            if z is None:
                return "-"
            return f"{z['err']:.3f} % FS" if z["value"] is not None else z["error"]
        print(k, "|", show(x), "->", show(y))
    print(f"the same: {same} of {len(a)}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="11-40", help="first-last")
    ap.add_argument("--out", help="write the records here (JSON)")
    ap.add_argument("--compare", nargs=2, metavar=("BEFORE", "AFTER"))
    args = ap.parse_args()
    if args.compare:
        compare(*args.compare)
        return
    first, last = (int(s) for s in args.seeds.split("-"))
    rows = scan(first, last)
    print(_summary(rows))
    if args.out:
        Path(args.out).write_text(json.dumps(rows, default=float))


if __name__ == "__main__":
    main()
