"""The climber's coverage plan round the tank (coverage/seam.py) beside the
walker's wrap plan alone, on the default 24 m × 9.6 m tank from the
climber's own start cell: turns, repetition, coverage and CPU time.

    PYTHONPATH=$PWD python bench/climber_plan_bench.py

Rows: the executor's mode (lanes up and down the wall, ``axis=1``) and
inspect_wall's sub-region mode (``regions=True``, any axis). CPU time by
time.process_time (numba compiled before the first timing).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from app.core.planner.coverage import figures, plan_coverage, rasterise, wrap_plan  # noqa: E402
from app.core.planner.coverage.wall import default_wall  # noqa: E402
from sim_robot.climber.kinematics import ClimberParams  # noqa: E402
from sim_robot.climber.sim import first_start  # noqa: E402


def main() -> None:
    blocked = rasterise(default_wall())
    start = first_start(blocked, ClimberParams(), default_wall().cell_m)
    wrap_plan(np.zeros((4, 9), bool), (0, 0), axis=1)  # compile
    print(f"default tank {blocked.shape[0]}×{blocked.shape[1]} cells, start {start}")
    print(f"{'mode':<22}{'planner':<14}{'turns':>7}{'repetition':>12}{'coverage':>10}{'CPU s':>8}")
    for mode, kw in (("executor (axis=1)", dict(regions=False, axis=1)),
                     ("sub-regions", dict(regions=True, axis=None))):
        for name, fn in (("walker", lambda kw=kw: plan_coverage(blocked, start, wrap=True, **kw)),
                         ("wrap_plan", lambda kw=kw: wrap_plan(blocked, start, **kw))):
            t = time.process_time()
            plan = fn()
            cpu = time.process_time() - t
            f = figures(blocked, start, plan.cells, wrap=True)
            print(f"{mode:<22}{name:<14}{f.turns:>7}{100 * f.repetition:>11.2f}%"
                  f"{100 * f.coverage:>9.1f}%{cpu:>8.2f}")


if __name__ == "__main__":
    main()
