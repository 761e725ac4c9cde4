"""Seed 003 §4.1 on the simulated climber: the 1 m square at 0.12 m/s and
0.35 rad/s, ten runs; yaw error (max, mean over the 1→2→3 leg) of wheel
odometry, gyro integration and their EKF fusion (app/core/localisation,
seed 003 eqs. 4–13) beside Table 2.

    PYTHONPATH=$PWD python bench/climber_square_bench.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from sim_robot.climber.square import TABLE2, square_table  # noqa: E402


def main() -> None:
    rows = square_table(10)
    print(
        "run   wheel max  mean   gyro max  mean  fused max  mean   |"
        " Table 2 before: max  mean   after: max  mean"
    )
    for (seed, d), ((bmax, bmean), (amax, amean)) in zip(rows, TABLE2, strict=True):
        (wmax, wmean), (gmax, gmean), (fmax, fmean) = d["wheel"], d["gyro"], d["fused"]
        print(
            f"{seed + 1:>3}  {wmax:>9.2f} {wmean:>5.2f}  {gmax:>8.2f} {gmean:>5.2f}"
            f"  {fmax:>9.2f} {fmean:>5.2f}   |"
            f" {bmax:>18.2f} {bmean:>5.2f} {amax:>12.2f} {amean:>5.2f}"
        )
    w = np.mean([d["wheel"][1] for _, d in rows])
    g = np.mean([d["gyro"][1] for _, d in rows])
    f = np.mean([d["fused"][1] for _, d in rows])
    print(
        f"mean of means: wheel {w:.2f}°, gyro {g:.2f}°, fused {f:.2f}° "
        f"({100 * (f - w) / w:+.1f} %); Table 2: 7.03° -> 0.78° (-88.9 %); goal: ≥ 90 % lower"
    )


if __name__ == "__main__":
    main()
