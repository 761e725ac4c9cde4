"""Turns in place at the lanes' ends and along the detours (sim_robot/climber/turns.py):
the relay's executor makes the same turns as the headless inspection."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.comm.wall_protocol import CoverageState
from app.core.planner.coverage.wall import Band, Disc, WallSpec
from sim_robot.climber import inspection as inspection_module
from sim_robot.climber import moves as moves_module
from sim_robot.climber.executor import InspectionExecutor
from sim_robot.climber.kinematics import ClimberParams
from sim_robot.climber.seam_detour import SeamDetour
from sim_robot.climber.turns import TURN_TOL_RAD, lane_change_turns, step_heading, turn_rate
from sim_robot.climber.wall_world import WallWorld

D = 0.1


def _collapse(headings: list[float]) -> list[float]:
    out: list[float] = []
    for h in headings:
        if not out or abs(out[-1] - h) > 1e-9:
            out.append(h)
    return out


def _recorder(monkeypatch, module, name: str, fn) -> list[float]:
    """Record the heading of every call of ``module.name`` (a turn's target)."""
    seen: list[float] = []

    def wrapped(*args):
        seen.append(args[-1])
        return fn(*args)

    monkeypatch.setattr(module, name, wrapped)
    return seen


def _fly(ex: InspectionExecutor, start: tuple[int, int], dt: float = 0.05,
         max_steps: int = 200_000) -> list[tuple[float, float, float, float, float]]:
    """An ideal body (no slip, no limits) driven by the executor, the probe read at
    every step, until the inspection ends: (x, y, θ, v, ω) of each step."""
    x, y, th = (start[1] + 0.5) * D - ex.lead, (start[0] + 0.5) * D, 0.0
    log, t = [], 0.0
    ex.start(t)
    for _ in range(max_steps):
        if ex.state != CoverageState.RUNNING:
            break
        ex.reading((x, y, th), 9.0)
        v, w = ex.step((x, y, th), t)
        log.append((x, y, th, v, w))
        mid = th + w * dt / 2
        x, y = (x + v * math.cos(mid) * dt) % ex.circ_m, y + v * math.sin(mid) * dt
        th = (th + w * dt + math.pi) % (2 * math.pi) - math.pi
        t += dt
    return log


def test_turn_rate_turns_the_short_way_and_stops_within_its_tolerance():
    assert turn_rate(0.0, math.pi / 2) == pytest.approx(0.3)
    assert turn_rate(math.radians(170), math.radians(-170)) > 0  # across ±π
    assert turn_rate(0.0, -0.05) == pytest.approx(-0.1)  # slows near the heading
    assert turn_rate(0.0, 0.9 * TURN_TOL_RAD) is None
    assert lane_change_turns((11, 4), (11, 5), (10, 5), 30) == (0.0, -math.pi / 2)
    assert lane_change_turns((0, 0), (0, 29), (1, 29), 30) == (math.pi, math.pi / 2)
    assert lane_change_turns((3, 4), (4, 4), (5, 4), 30) == (None, None)  # along a lane
    assert step_heading((2, 0), (2, 29), 30) == pytest.approx(math.pi)  # round the seam


def test_the_relays_executor_turns_in_place_where_inspect_wall_does(monkeypatch):
    """The same wall and start: the headless inspection (steering on the true pose,
    turns in place, no detours) and the relay's executor (flying an ideal body)
    turn to the same headings in the same order, one pair per lane change; the
    executor turns with the body standing (v = 0), ends each turn within the
    tolerance, and covers every reachable cell. Told not to, it makes no turn."""
    spec = WallSpec(2.0 / math.pi, 0.8, D, nozzles=(Disc(1.0, 0.4, 0.2),))
    world = WallWorld(spec, seed=1)
    start = (0, 3)
    headless = _recorder(monkeypatch, inspection_module, "turn_to", inspection_module.turn_to)
    res = inspection_module.inspect_wall(world, start, seed=1, lanes="vertical",
                                         turns_in_place=True, x_fix_lanes=0)
    assert res.probed == res.planned
    relay = _recorder(monkeypatch, moves_module, "turn_rate", turn_rate)
    ex = InspectionExecutor(world.blocked, D, start, ClimberParams(), turns_in_place=True)
    lane_changes = sum(1 for a, b in zip(ex.cells, ex.cells[1:], strict=False)
                       if a[0] == b[0] and a[1] != b[1])
    log = _fly(ex, start)
    assert ex.state == CoverageState.DONE and ex.covered.sum() == ex.reachable
    assert lane_changes > 5 and len(_collapse(headless)) > 1.5 * lane_changes
    assert _collapse(relay) == _collapse(headless)
    assert ex.turns >= len(_collapse(relay))
    log = log[1:]  # (the first step's probe is on its cell: v = 0 there too)
    turning = [(th, w) for _, _, th, v, w in log if v == 0.0 and w != 0.0]
    assert len(turning) > 20 * lane_changes  # each turn takes many steps at 0.3 rad/s
    # where each turn ended (the heading of the first step after it) is its target
    ends = [log[k + 1][2] for k in range(len(log) - 1)
            if log[k][3] == 0.0 and log[k][4] != 0.0 and log[k + 1][3] != 0.0]
    assert len(ends) >= lane_changes
    assert all(min(abs((e - h + math.pi) % (2 * math.pi) - math.pi) for h in relay)
               < TURN_TOL_RAD + 0.02 for e in ends)

    blended = InspectionExecutor(world.blocked, D, start, ClimberParams())
    log = _fly(blended, start)
    assert blended.state == CoverageState.DONE and blended.turns == 0
    assert not any(v == 0.0 and w != 0.0 for *_, v, w in log[1:])


def test_along_a_detour_the_executor_faces_each_leg(monkeypatch):
    """A detour to a vertical seam runs along the lane's end row and back: the
    executor turns to face the way to the seam, then the way back, before driving
    each leg (as inspect_wall's detours with turns in place)."""
    blocked = np.zeros((4, 24), bool)
    seams = (Band(0.05, 0.0, 0.05, 0.4, 0.02, crossable=True),
             Band(1.25, 0.0, 1.25, 0.4, 0.02, crossable=True))  # columns 0 and 12
    det = SeamDetour(blocked, seams, D, max_lanes=3, max_steps=8)
    routes: list[tuple[tuple[int, int], list[tuple[int, int]]]] = []
    plan_route = det.route

    def route(here, step_ok=None):
        r = plan_route(here, step_ok)
        if r:
            routes.append((here, r))
            events.append(("detour", len(routes) - 1))
        return r

    det.route = route
    events: list[tuple[str, object]] = []

    def rate(now, heading):
        if not events or events[-1] != ("turn", heading):
            events.append(("turn", heading))
        return turn_rate(now, heading)

    monkeypatch.setattr(moves_module, "turn_rate", rate)
    ex = InspectionExecutor(blocked, D, (0, 3), ClimberParams(), detour=det, turns_in_place=True)
    _fly(ex, (0, 3))
    assert ex.state == CoverageState.DONE and ex.covered.sum() == ex.reachable
    assert len(routes) >= 2
    for k, (here, r) in enumerate(routes):
        i = events.index(("detour", k))
        turns = [h for kind, h in events[i + 1:i + 3] if kind == "turn"]
        way_out = step_heading(here, r[0], blocked.shape[1])
        way_back = step_heading(r[-2], r[-1], blocked.shape[1])
        assert {round(abs(way_out), 6), round(abs(way_back), 6)} == {0.0, round(math.pi, 6)}
        assert turns == [way_out, way_back]


def test_a_turn_keeps_its_rate_on_a_stale_estimate():
    """The probe is slowed on an estimate older than FRESH_S, a turn in place is
    not: a rate that changes from one control period to the next, read by the
    relay's odometry from the gyro's last sample of each (thinned) report, left
    the heading degrees off after the turns at 40x (docs/climber.md)."""
    from sim_robot.climber.executor import FRESH_S

    blocked = np.zeros((3, 12), bool)
    ex = InspectionExecutor(blocked, D, (0, 3), ClimberParams(), turns_in_place=True)
    x, y, th, t, dt = (3.5) * D - ex.lead, 0.5 * D, 0.0, 0.0, 0.05
    ex.start(t)
    for _ in range(20_000):
        ex.reading((x, y, th), 9.0)
        v, w = ex.step((x, y, th), t)
        if t > 0 and v == 0.0 and abs(w) == pytest.approx(0.3):
            break
        x, y = x + v * math.cos(th) * dt, y + v * math.sin(th) * dt
        th = (th + w * dt + math.pi) % (2 * math.pi) - math.pi
        t += dt
    else:
        raise AssertionError("no turn in place")
    assert ex.step((x, y, th), t, t - 5 * FRESH_S) == (0.0, w)
