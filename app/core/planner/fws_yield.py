"""Yielding for the 4WS navigator's safety stop (step 4 of
:mod:`fws_navigator`): before the robot brakes to rest because a tracked
person threatens its band, check that standing there keeps it out of that
person's predicted way; if not, drive on along the band or step aside.

The idea is the skid-steer robot's braking contingency (docs/planning.md:
every command must leave a way to stop clear of the predictions — the
inevitable-collision-state idea of Fraichard and Asama), applied to the
choice the 4WS robot makes when it stops: the people are the robot's own
tracks (x, y, vx, vy, r) with constant-velocity predictions, never the
simulator's truth.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["choose"]


def choose(c, field, tracks, pose: np.ndarray, v_now: float, band: np.ndarray | None):
    """Where to go when a tracked person threatens the band: None to stand
    (brake to rest here, as step 4 always did), "on" to drive on along the
    band, or (v, ω) to step aside: brake, then back straight away, or back
    or forward on a slow arc to either side (``yield_back_mps``,
    ``yield_turn_rps``: within the counter-phase turning radius).

    Each choice is rolled out over ``yield_horizon_s`` against every track's
    constant-velocity prediction (the robot's own tracking, never the
    world's truth): standing is kept while it stays ``yield_margin_m``
    clear of them; otherwise the choice with the larger least gap to them
    (and clear of the static map) is taken, if it beats standing — the
    braking contingency of the skid-steer robot's governor
    (docs/planning.md), applied to the 4WS robot's stop.

    ``c``: the navigator's ``FwsNavConfig``; ``field``: the static map's
    clearance (``distance(xy)`` in metres); ``tracks``: k × 5; ``band``: the
    TEB band pure pursuit follows (None: driving on is not a choice, as in
    a turn in place)."""
    obs = np.asarray(tracks, dtype=float).reshape(-1, 5)
    if not len(obs):
        return None
    ts = np.arange(0.0, c.yield_horizon_s + 1e-9, 0.1)
    people = obs[None, :, :2] + ts[:, None, None] * obs[None, :, 2:4]  # T × k × 2
    reach = obs[:, 4] + c.robot_radius_m

    def gap(xy: np.ndarray) -> float:
        d = np.linalg.norm(people - xy[:, None, :], axis=2) - reach
        return float(d.min())

    def static_ok(xy: np.ndarray) -> bool:
        return bool(np.min(field.distance(xy)) >= c.robot_radius_m + 0.05)

    heading = np.array([math.cos(pose[2]), math.sin(pose[2])])
    v0 = max(v_now, 0.0)
    stop_d = np.minimum(v0 * ts - 0.5 * c.brake_mps2 * ts ** 2,
                        v0 ** 2 / (2 * c.brake_mps2))
    stand = pose[:2] + np.maximum(stop_d, 0.0)[:, None] * heading
    g_stand = gap(stand)
    if g_stand >= c.yield_margin_m:
        return None
    best, g_best = None, g_stand + 0.05
    # stepping aside: brake, then a slow arc or line (back straight, back or
    # forward on the tightest counter-phase arcs either side)
    t_b = v0 / c.brake_mps2
    s_b = float(v0 * t_b / 2)
    after = np.maximum(ts - t_b, 0.0)
    rate = c.yield_turn_rps
    base = pose[:2] + s_b * heading
    for v, w in ((-c.yield_back_mps, 0.0), (-c.yield_back_mps, rate),
                 (-c.yield_back_mps, -rate), (c.yield_back_mps, rate),
                 (c.yield_back_mps, -rate)):
        th = pose[2] + w * after
        if w:
            x = base[0] + v / w * (np.sin(th) - math.sin(pose[2]))
            y = base[1] - v / w * (np.cos(th) - math.cos(pose[2]))
        else:
            x = base[0] + v * after * heading[0]
            y = base[1] + v * after * heading[1]
        pre = ts < t_b
        roll = np.column_stack([x, y])
        roll[pre] = stand[pre]
        if static_ok(roll):
            g = gap(roll)
            if g > g_best:
                best, g_best = (v, w), g
    if band is not None:
        seg = np.linalg.norm(np.diff(band, axis=0), axis=1)
        sb = np.concatenate([[0.0], np.cumsum(seg)])
        t_a = max(c.v_max_mps - v0, 0.0) / c.accel_mps2  # speeding up to the top
        dist = np.where(ts <= t_a, v0 * ts + 0.5 * c.accel_mps2 * ts ** 2,
                        v0 * t_a + 0.5 * c.accel_mps2 * t_a ** 2 + c.v_max_mps * (ts - t_a))
        dist = np.minimum(dist, sb[-1])
        on = np.column_stack([np.interp(dist, sb, band[:, 0]),
                              np.interp(dist, sb, band[:, 1])])
        if sb[-1] > 1.0 and static_ok(on) and gap(on) > g_best:
            best, g_best = "on", gap(on)
    return best
