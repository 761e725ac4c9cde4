"""Constant-velocity rollouts of a command against the map's clearance field and
the predicted moving obstacles (numba kernels): what the hybrid planner's safety
governor scores its candidate commands with. A slow obstacle's disc grows with
time (a person standing may set off); see :func:`rollout_ramp`."""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def _growth(obs, grow, grow_below, grow_moving=0.0):
    """Per obstacle, how fast its predicted disc grows (m/s): ``grow`` for
    one standing, falling linearly to 0 at ``grow_below`` m/s and above, but
    never below ``grow_moving`` (the uncertainty of a walker's velocity)."""
    out = np.full(obs.shape[0], grow_moving)
    if grow > 0.0 and grow_below > 0.0:
        for m in range(obs.shape[0]):
            sp = math.hypot(obs[m, 2], obs[m, 3])
            if sp < grow_below:
                out[m] = max(grow * (1.0 - sp / grow_below), grow_moving)
    return out


@njit(cache=True)
def rollout_clearance(
    x,
    y,
    th,
    v,
    w,
    horizon,
    sdt,
    dist,
    res,
    ox,
    oy,
    obs,
    robot_r,
    grow=0.0,
    grow_cap=0.0,
    grow_below=0.0,
    grow_moving=0.0,
):
    """Smallest surface clearance along the arc (v, ω) over the horizon (from
    the first step on, so moves away from a near obstacle score higher),
    against the static field and constant-velocity moving obstacles (a slow
    one's disc growing with time, see rollout_ramp)."""
    dmin = 1e9
    steps = int(horizon / sdt + 0.5)
    h, wd = dist.shape
    rate = _growth(obs, grow, grow_below, grow_moving)
    for s in range(1, steps + 1):
        x += v * math.cos(th) * sdt
        y += v * math.sin(th) * sdt
        th += w * sdt
        c = int(math.floor((x - ox) / res))
        r = int(math.floor((y - oy) / res))
        if r < 0 or r >= h or c < 0 or c >= wd:
            d = -1.0
        else:
            d = dist[r, c] - robot_r
        t = s * sdt
        for m in range(obs.shape[0]):
            dd = math.hypot(x - obs[m, 0] - obs[m, 2] * t, y - obs[m, 1] - obs[m, 3] * t)
            dd -= obs[m, 4] + robot_r + min(rate[m] * t, grow_cap)
            if dd < d:
                d = dd
        if d < dmin:
            dmin = d
    return dmin


@njit(cache=True)
def rollout_ramp(
    x,
    y,
    th,
    vc,
    wc,
    vt,
    wt,
    acc,
    alpha,
    horizon,
    sdt,
    dist,
    res,
    ox,
    oy,
    obs,
    robot_r,
    phi=np.nan,
    grow=0.0,
    grow_cap=0.0,
    grow_below=0.0,
    grow_moving=0.0,
    stop_after=np.inf,
):
    """Drive from (vc, ω_c) towards the target (vt, ωt) at the acceleration
    limits, then hold it; or, with a heading phi, stop and turn in place
    (|ωt| as turn rate) until facing phi, then drive straight at vt. With a
    finite ``stop_after`` the motion is a contingency: after that many
    seconds the robot brakes to rest at the limits and stands there for the
    rest of the horizon. Every rollout is checked against
    the static clearance field and the
    constant-velocity prediction of every moving obstacle. A slow obstacle
    (a person standing may set off in any direction) is predicted as a disc
    growing with time: its radius + min(rate · t, grow_cap), rate = grow for
    one standing, falling linearly to 0 at grow_below m/s (grow 0: no
    growth), and at least grow_moving for any. Returns (smallest static
    clearance, smallest clearance to a moving obstacle, time of the first
    contact with anything or +inf)."""
    d_static = 1e9
    d_moving = 1e9
    t_hit = math.inf
    steps = int(horizon / sdt + 0.5)
    h, wd = dist.shape
    v = vc
    w = wc
    turn = not math.isnan(phi)
    rate = _growth(obs, grow, grow_below, grow_moving)
    for s in range(1, steps + 1):
        tv = vt
        tw = wt
        if (s - 1) * sdt >= stop_after:
            tv = 0.0
            tw = 0.0
        elif turn:
            err = (phi - th + math.pi) % (2.0 * math.pi) - math.pi
            if abs(err) > 0.2:
                tv = 0.0
                tw = abs(wt) if err > 0 else -abs(wt)
            else:
                tw = min(max(2.0 * err, -abs(wt)), abs(wt))
        v += min(max(tv - v, -acc * sdt), acc * sdt)
        w += min(max(tw - w, -alpha * sdt), alpha * sdt)
        x += v * math.cos(th) * sdt
        y += v * math.sin(th) * sdt
        th += w * sdt
        c = int(math.floor((x - ox) / res))
        r = int(math.floor((y - oy) / res))
        if r < 0 or r >= h or c < 0 or c >= wd:
            d = -1.0
        else:
            d = dist[r, c] - robot_r
        if d < d_static:
            d_static = d
        t = s * sdt
        for m in range(obs.shape[0]):
            dd = math.hypot(x - obs[m, 0] - obs[m, 2] * t, y - obs[m, 1] - obs[m, 3] * t)
            dd -= obs[m, 4] + robot_r + min(rate[m] * t, grow_cap)
            if dd < d_moving:
                d_moving = dd
            if dd < d:
                d = dd
        if d <= 0.0 and t < t_hit:
            t_hit = t
    return d_static, d_moving, t_hit


@njit(cache=True)
def rollout_many(
    x,
    y,
    th,
    vc,
    wc,
    cands,
    acc,
    alpha,
    horizon,
    sdt,
    dist,
    res,
    ox,
    oy,
    obs,
    robot_r,
    grow=0.0,
    grow_cap=0.0,
    grow_below=0.0,
    grow_moving=0.0,
    stop_after=np.inf,
):
    """rollout_ramp for every candidate row (v_target, ω_target, phi) of
    cands; rows of (static clearance, moving clearance, first contact)."""
    out = np.empty((cands.shape[0], 3))
    for i in range(cands.shape[0]):
        ds, dm, t_hit = rollout_ramp(
            x,
            y,
            th,
            vc,
            wc,
            cands[i, 0],
            cands[i, 1],
            acc,
            alpha,
            horizon,
            sdt,
            dist,
            res,
            ox,
            oy,
            obs,
            robot_r,
            cands[i, 2],
            grow,
            grow_cap,
            grow_below,
            grow_moving,
            stop_after,
        )
        out[i, 0] = ds
        out[i, 1] = dm
        out[i, 2] = t_hit
    return out
