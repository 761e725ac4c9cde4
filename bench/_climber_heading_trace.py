"""A trace of the wall EKF's heading against the simulator's truth (for
bench/climber_link_bench.py ``--heading-log``; the robot never reads it): about
every half second of the board's time, a line of JSON with the true heading, the
belief's and its σθ, the board's gravity heading and its error against the truth,
the turn the true accelerometer bias gives it, (b_x cos θ − b_y sin θ)/g, the
filter's learnt bias and its σ, the true bias, the gyro's rate less the standstill
bias the relay removed against the true rate, and the gravity innovation."""

from __future__ import annotations

import json
import math

G = 9.81


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def trace_heading(sim, path: str, every_s: float = 0.5) -> None:
    """Wrap the relay's odometry update; writes lines to ``path`` as the run goes."""
    odom, mcu, body = sim.relay.odom, sim.model, sim.body
    out = open(path, "w", encoding="utf-8")  # noqa: SIM115 (open for the run's length)
    update = odom.update
    last = [-math.inf]

    def wrapped(mcu_time_ms, enc_l, enc_r, yaw_rate_rps, imu_yaw_rad=None):
        update(mcu_time_ms, enc_l, enc_r, yaw_rate_rps, imu_yaw_rad)
        t = mcu_time_ms / 1000.0
        if t - last[0] < every_s:
            return
        last[0] = t
        ekf = odom.ekf
        p = ekf.covariance
        th_true = body.s.theta_rad
        bx_t, by_t = (float(v) for v in mcu.accel.bias)
        c, s = math.cos(th_true), math.sin(th_true)
        bx, by = ekf.accel_bias
        rec = {
            "t": round(t, 2), "th_true": round(th_true, 4),
            "th_err": round(_wrap(ekf.pose[2] - th_true), 5),
            "sth": round(math.sqrt(max(0.0, p[2, 2])), 5),
            "g_err": None if imu_yaw_rad is None else round(_wrap(imu_yaw_rad - th_true), 5),
            "bias_turn_true": round((bx_t * c - by_t * s) / G, 5),
            "bias_turn_belief": round((bx * c - by * s) / G, 5),
            "b": [round(bx, 4), round(by, 4)], "b_true": [round(bx_t, 4), round(by_t, 4)],
            "sb": [round(math.sqrt(max(0.0, p[9, 9])), 4),
                   round(math.sqrt(max(0.0, p[10, 10])), 4)],
            "gyro_bias_err": round(mcu.imu.bias - float(getattr(odom, "bias", 0.0)), 6),
            "innov": round(ekf.gravity_innov, 5),
            "refused": ekf.rejected["gravity"], "resets": ekf.resets["gravity"],
        }
        out.write(json.dumps(rec) + "\n")
        out.flush()

    odom.update = wrapped
