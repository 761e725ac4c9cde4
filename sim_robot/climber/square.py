"""The odometry test of seed 003 §4.1 on the simulated climber: 1 m sides at
0.12 m/s, 90° turns at 0.35 rad/s, ten runs; the yaw error of each heading
estimate against the true heading, as max and mean over the 1→2→3 leg
(a side, the turn at 2, the next side), as in Table 2.

The run records what the robot's sensors give — encoder ticks
(sim_robot.sensors.WheelEncoders) and gyro rates (sim_robot.sensors.Imu) —
so any estimator can be replayed over the same run: wheel odometry
(encoders only), gyro integration, and the fusion of both by the EKF of
app/core/localisation (seed 003 eqs. 4–13). As there, the gyro's bias is
the mean of STANDSTILL_S of readings at rest before the run.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from app.core.localisation.ekf import OdometryEkf

from ..sensors import Imu, WheelEncoders
from .kinematics import ClimberBody, ClimberParams, ClimberState

STANDSTILL_S = 10.0

TABLE2 = (  # seed 003 Table 2: (max, mean) before fusion, (max, mean) after, degrees
    ((13.27, 6.38), (2.12, 0.85)),
    ((12.75, 6.03), (1.80, 0.68)),
    ((13.99, 8.60), (0.48, 0.02)),
    ((12.75, 6.06), (3.37, 0.60)),
    ((13.60, 7.64), (3.57, 1.82)),
    ((13.07, 7.00), (2.18, 0.56)),
    ((13.63, 6.98), (2.06, 0.51)),
    ((14.42, 8.79), (2.55, 0.53)),
    ((13.19, 6.40), (3.35, 1.38)),
    ((13.92, 6.43), (2.02, 0.85)),
)


@dataclass
class SquareRun:
    """Per step: time, true heading, encoder ticks, gyro rate."""

    dt_s: float
    t_s: np.ndarray
    true_yaw: np.ndarray
    ticks: np.ndarray  # (n, 2) left, right
    gyro_rps: np.ndarray
    leg: np.ndarray  # bool: inside the 1→2→3 leg
    ticks_per_m: float
    track_m: float
    gyro_rest_rps: np.ndarray  # readings at rest before the run


def run_square(seed: int = 0, dt_s: float = 0.01, params: ClimberParams | None = None) -> SquareRun:
    """Drive the square once (anticlockwise from facing +x) and record."""
    params = params or ClimberParams()
    rng = np.random.default_rng(1000 + seed)
    body = ClimberBody(params, ClimberState(1.0, 1.0, 0.0), seed=seed)
    enc = WheelEncoders(rng, params.wheel_radius_m, params.ticks_per_rev, slip=0.0)
    imu = Imu(rng)
    rest = np.array([imu.sample(dt_s, 0.0) for _ in range(int(STANDSTILL_S / dt_s))])
    plan: list[tuple[float, float, float]] = []
    for _ in range(4):
        plan.append((0.12, 0.0, 1.0 / 0.12))
        plan.append((0.0, 0.35, (math.pi / 2) / 0.35))
    t, rows, leg = 0.0, [], []
    for k, (v, w, dur) in enumerate(plan):
        n = int(round(dur / dt_s))
        for i in range(n + 40):  # 0.4 s more to come to rest
            cmd = (v, w) if i < n else (0.0, 0.0)
            vl, vr, w_true = body.step(*cmd, dt_s)
            tl, tr = enc.step(dt_s, vl, vr)
            rows.append((t, body.s.theta_rad, tl, tr, imu.sample(dt_s, w_true)))
            leg.append(k in (0, 1, 2))
            t += dt_s
    a = np.array(rows)
    return SquareRun(
        dt_s,
        a[:, 0],
        a[:, 1],
        a[:, 2:4].astype(np.int64),
        a[:, 4],
        np.array(leg),
        enc.ticks_per_m,
        params.track_m,
        rest,
    )


def wheel_yaw(run: SquareRun) -> np.ndarray:
    """Heading from the encoders alone (eqs. 1–2: integrate ω = (v_r − v_l)/track)."""
    d = np.diff(run.ticks, axis=0, prepend=run.ticks[:1]) / run.ticks_per_m
    return np.cumsum((d[:, 1] - d[:, 0]) / run.track_m)


def gyro_yaw(run: SquareRun) -> np.ndarray:
    """Heading from integrating the gyro alone, standstill bias removed."""
    return np.cumsum((run.gyro_rps - float(np.mean(run.gyro_rest_rps))) * run.dt_s)


def fused_yaw(run: SquareRun) -> np.ndarray:
    """Heading from the EKF fusing encoders and gyro (seed 003 eqs. 4–13,
    app/core/localisation/ekf.py), gyro bias removed by the standstill mean."""
    bias = float(np.mean(run.gyro_rest_rps))
    ekf = OdometryEkf(track_m=run.track_m)
    d = np.diff(run.ticks, axis=0, prepend=run.ticks[:1]) / run.ticks_per_m
    out = np.empty(len(run.t_s))
    for k in range(len(run.t_s)):
        ekf.predict(run.dt_s)
        ekf.update_encoders(float(d[k, 0]), float(d[k, 1]), run.dt_s)
        ekf.update_imu_yaw_rate(float(run.gyro_rps[k]) - bias)
        out[k] = ekf.pose[2]
    return np.unwrap(out)


def yaw_error_deg(run: SquareRun, estimate: np.ndarray) -> tuple[float, float]:
    """(max, mean) |estimate − true| over the 1→2→3 leg, degrees."""
    err = np.abs((estimate - np.unwrap(run.true_yaw) + math.pi) % (2 * math.pi) - math.pi)
    err = np.degrees(err[run.leg])
    return float(err.max()), float(err.mean())


def square_table(
    runs: int = 10, estimators: dict[str, Callable[[SquareRun], np.ndarray]] | None = None
):
    """Rows of (run, {estimator: (max, mean)}) for ``runs`` seeded runs."""
    estimators = estimators or {"wheel": wheel_yaw, "gyro": gyro_yaw, "fused": fused_yaw}
    out = []
    for seed in range(runs):
        run = run_square(seed)
        out.append((seed, {name: yaw_error_deg(run, fn(run)) for name, fn in estimators.items()}))
    return out
