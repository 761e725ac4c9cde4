"""Fuzz both frame decoders with seeded random and mutated inputs.

Prints, for the robot link's FrameDecoder and the MCU serial McuDecoder: the
number of inputs, how many raised an exception (goal 0), how many lost the
good frame sent after the damage (goal 0), the inputs by mutation, the drops
counted by reason, and the rate.

    .venv/bin/python bench/fuzz.py               # 100 000 inputs per decoder
    .venv/bin/python bench/fuzz.py -n 20000 --seed 3
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.fuzz_cases import fuzz_link, fuzz_mcu  # noqa: E402


def report(name: str, run, n: int, seed: int) -> int:
    t0 = time.perf_counter()
    r = run(n, seed)
    dt = time.perf_counter() - t0
    print(f"{name}: {r.cases} inputs, seed {seed}, {dt:.1f} s ({r.cases / dt:.0f}/s)")
    print(f"  raised an exception       {r.raised:8d}   (goal 0)")
    print(f"  good frame after damage lost {r.sentinel_lost:5d}   (goal 0)")
    print(f"  frames decoded            {r.frames_decoded:8d}")
    print("  inputs by mutation        " + ", ".join(f"{k} {v}" for k, v in
                                                     sorted(r.by_mutation.items())))
    print("  drops by reason           " + ", ".join(f"{k} {v}" for k, v in
                                                     sorted(r.drops.items())))
    for e in r.first_errors:
        print("  first errors:\n" + e)
    return r.raised + r.sentinel_lost


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-n", type=int, default=100_000, help="inputs per decoder")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    bad = report("robot link FrameDecoder", fuzz_link, a.n, a.seed)
    bad += report("MCU serial McuDecoder", fuzz_mcu, a.n, a.seed + 1)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
