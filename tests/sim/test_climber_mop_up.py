"""The relay executor's mop-up planned apart (sim_robot/climber/executor_route.py): the
route to the cells its record missed is planned on a worker thread while the robot
holds still, and taken only if nothing has been missed since that it does not know of."""

from __future__ import annotations

import threading

import numpy as np

from app.comm.wall_protocol import CoverageState
from sim_robot.climber.executor import InspectionExecutor
from sim_robot.climber.kinematics import ClimberParams

D = 0.1


def test_the_mop_up_is_planned_apart_while_the_robot_holds_still_and_again_if_stale():
    ex = InspectionExecutor(np.zeros((6, 8), bool), D, (0, 2), ClimberParams())
    ex.plan_apart = True
    release = threading.Event()
    calls: list[tuple[tuple[int, int], set, bool]] = []

    def slow_plan(start, missed):  # (a planner that takes long: until released)
        released = release.wait(10)
        calls.append((start, {tuple(int(v) for v in c) for c in np.argwhere(missed)},
                      released))
        return [tuple(int(v) for v in c) for c in np.argwhere(missed)]

    ex._mop_route = slow_plan
    ex.start(0.0)
    ex.covered[:] = True  # the sweep driven and filed, but for one cell ...
    ex.covered[3, 5] = False
    ex.index = len(ex.cells)
    last = ex.cells[-1]
    pose = ((last[1] + 0.5) * D - ex.lead, (last[0] + 0.5) * D, 0.0)
    assert ex.step(pose, 0.95, 0.95) == (0.0, 0.0)  # the plan begun (the visit at hand filed)
    visits = ex.visits
    for t in (1.0, 1.05, 1.1):  # the steps go on, the robot held still, the plan pending
        ex.reading(pose, 9.0)  # (its probe over the last cell: one visit, not one a step)
        assert ex.step(pose, t, t) == (0.0, 0.0)
        assert ex.state == CoverageState.RUNNING and ex.index == len(ex.cells)
    assert ex.visits == visits + 1
    ex.covered[4, 6] = False  # ... and one an x fix takes back while it is planned
    first = ex._mop_plan
    release.set()
    first.thread.join()
    assert ex.step(pose, 1.15, 1.15) == (0.0, 0.0)  # stale: planned again
    assert ex.mop_replans == 1 and ex.mop_ups == 0
    ex._mop_plan.thread.join()
    n = len(ex.cells)
    v, w = ex.step(pose, 1.2, 1.2)  # the route taken, and driven
    assert (v, w) != (0.0, 0.0)
    assert ex.cells[n:] == [(3, 5), (4, 6)] and ex.mop_ups == 1
    assert [c[:2] for c in calls] == [(last, {(3, 5)}), (last, {(3, 5), (4, 6)})]
    assert all(released for *_, released in calls)  # (no step waited for the planner)
