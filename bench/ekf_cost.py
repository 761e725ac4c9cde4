"""CPU time per odometry report of the EKFs (app/core/localisation/ekf.py and
wall_ekf.py): the patrol robot's six-state filter (an advance with the encoders and the
gyro) and the climber's eleven-state wall filter (the same, then the gravity heading).

    PYTHONPATH=$PWD python bench/ekf_cost.py [--reports 4000] [--repeats 3]

Prints µs of CPU (``time.process_time``) per report, after a warm-up that loads the
compiled kernels.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from app.core.localisation.ekf import OdometryEkf
from app.core.localisation.wall_ekf import WallEkf


def _cost(make, gravity: bool, reports: int, seed: int) -> float:
    ekf = make()
    rng = np.random.default_rng(seed)
    for _ in range(50):  # warm-up: the kernels are loaded from numba's cache
        ekf.advance(0.05, 0.005, 0.005, 0.0)
    noise = rng.normal(size=(reports, 4))
    t = time.process_time()
    for dl, dr, g, th in noise:
        ekf.advance(0.05, 0.005 + 1e-4 * dl, 0.005 + 1e-4 * dr, 0.01 * g)
        if gravity:
            ekf.update_gravity_heading(ekf.pose[2] + 0.001 * th)
    return (time.process_time() - t) / reports * 1e6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--reports", type=int, default=4000)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    for r in range(a.repeats):
        odo = _cost(lambda: OdometryEkf(track_m=0.3), False, a.reports, r)
        wall = _cost(lambda: WallEkf(1.0, 1.0, 0.5, track_m=0.22), True, a.reports, r)
        print(f"run {r}: six-state EKF {odo:.0f} µs per report; "
              f"wall EKF {wall:.0f} µs per report (with the gravity heading)")


if __name__ == "__main__":
    main()
