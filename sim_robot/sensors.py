"""Sensor models sampled by the MCU: gas (MQ-style), DHT22, ultrasonic, battery, IMU.

Each model is a small class with ``sample(...)`` taking sim time and the true
quantity; noise comes from a numpy Generator so a seed reproduces a run.
"""

from __future__ import annotations

import math

import numpy as np


class GasSensor:
    """MQ-style gas sensor: first-order lag (time constant ``tau_s``) towards the true
    concentration, plus white noise and a slow baseline drift; output in %LEL.

    The output is the transmitter's, signed and bounded by its range
    (``OUT_MIN_LEL``..``OUT_MAX_LEL``, like a 4-20 mA loop read below 4 mA or above
    20 mA): near zero the noise reads either side of it, a drifted or broken element
    (``offset_lel`` < 0) reads below zero, which the desk's gas model calls a sensor
    fault, and a saturated one reads above 100 %LEL (over-range)."""

    OUT_MIN_LEL = -25.0
    OUT_MAX_LEL = 110.0

    def __init__(self, rng: np.random.Generator, tau_s: float = 4.0, noise_lel: float = 0.15,
                 drift_lel_per_h: float = 0.3) -> None:
        self.rng = rng
        self.tau_s = tau_s
        self.noise = noise_lel
        self.drift_rate = drift_lel_per_h / 3600.0
        self.state = 0.0
        self.drift = 0.0
        self.offset_lel = 0.0  # a faulty element's offset (configuration, tests)
        self._t: float | None = None

    def sample(self, t_s: float, true_lel: float) -> float:
        if self._t is None:  # a warmed-up sensor starts at the true value
            self.state, dt = true_lel, 0.0
        else:
            dt = max(0.0, t_s - self._t)
        self._t = t_s
        self.state += (1.0 - math.exp(-dt / self.tau_s)) * (true_lel - self.state)
        self.drift += self.drift_rate * dt * (1.0 + 0.5 * self.rng.standard_normal())
        out = (self.state + self.drift + self.offset_lel
               + self.noise * self.rng.standard_normal())
        return float(min(self.OUT_MAX_LEL, max(self.OUT_MIN_LEL, out)))


class Dht22:
    """DHT22-like temperature/humidity: a new reading every ``period_s``, quantised
    to 0.1 degC / 0.1 %RH, with small noise; between updates it repeats the last."""

    def __init__(self, rng: np.random.Generator, period_s: float = 2.0) -> None:
        self.rng = rng
        self.period_s = period_s
        self._next = -math.inf
        self.temp_c = 0.0
        self.humidity_pct = 0.0
        self.updates = 0

    def sample(self, t_s: float, temp_c: float, humidity_pct: float) -> tuple[float, float]:
        if t_s >= self._next:
            self._next = t_s + self.period_s if self._next == -math.inf else \
                self._next + self.period_s * max(1, math.ceil((t_s - self._next) / self.period_s))
            t = temp_c + 0.1 * self.rng.standard_normal()
            h = humidity_pct + 0.5 * self.rng.standard_normal()
            self.temp_c = round(t * 10) / 10
            self.humidity_pct = round(min(100.0, max(0.0, h)) * 10) / 10
            self.updates += 1
        return self.temp_c, self.humidity_pct


class Ultrasonic:
    """Three front ultrasonic rangers (left +35 deg, front, right -35 deg) with a
    +-12 deg cone, mounted ``mount_m`` ahead of the centre; 0.02..4 m, 4 m = nothing."""

    ANGLES = (math.radians(35), 0.0, math.radians(-35))
    MIN_M, MAX_M = 0.02, 4.0

    def __init__(self, rng: np.random.Generator, mount_m: float = 0.2,
                 cone_rad: float = math.radians(12)) -> None:
        self.rng = rng
        self.mount_m = mount_m
        offs = np.linspace(-cone_rad, cone_rad, 7)
        self._rel = np.concatenate([a + offs for a in self.ANGLES])

    def sample(self, world, x: float, y: float, theta: float) -> tuple[float, float, float]:
        sx = x + self.mount_m * math.cos(theta)
        sy = y + self.mount_m * math.sin(theta)
        rng, _ = world.raycast(sx, sy, theta + self._rel, self.MAX_M, step_m=0.02)
        per = rng.reshape(3, -1).min(axis=1)
        out = []
        for r in per:
            if not math.isfinite(r) or r > self.MAX_M:
                out.append(self.MAX_M)
            else:
                r = r + 0.005 * self.rng.standard_normal() + 0.01 * r * self.rng.standard_normal()
                out.append(float(min(self.MAX_M, max(self.MIN_M, r))))
        return out[0], out[1], out[2]


class Battery:
    """6S Li-ion pack (24 V class: 25.2 V full, 18 V empty): open-circuit voltage
    from state of charge, an internal-resistance drop, idle and drive currents;
    charges on the dock."""

    CELLS = 6

    def __init__(self, capacity_ah: float = 10.0, soc: float = 0.92,
                 r_internal_ohm: float = 0.12) -> None:
        self.capacity_as = capacity_ah * 3600.0
        self.soc = soc
        self.r = r_internal_ohm
        self.current_a = 0.0

    def step(self, dt: float, wheel_speed_mps: float, charging: bool) -> float:
        i = 0.6 + 3.5 * min(1.0, wheel_speed_mps)
        if charging:
            i -= 3.0
        self.current_a = i
        self.soc = min(1.0, max(0.0, self.soc - i * dt / self.capacity_as))
        return self.voltage()

    def voltage(self) -> float:
        cell = 3.45 + 0.75 * self.soc - 0.45 * (1 - self.soc) ** 6
        return self.CELLS * cell - self.r * self.current_a


class Imu:
    """Yaw-rate gyro: a turn-on bias, a slow bias wander about it, and white noise.

    The wander is a first-order Gauss-Markov process (the usual model of a MEMS
    gyro's bias instability): over seconds to minutes it is the random walk of
    ``walk_rps_per_sqrt_s``; over hours it stays within about
    ``walk · sqrt(tau / 2)`` of the turn-on bias (0.5 deg/s with the defaults),
    where a pure random walk would keep growing (about 6 deg/s after three days).
    Stepped exactly for any ``dt``: b ← μ + (b − μ)·φ + σ·sqrt(1 − φ²)·n, φ = e^(−dt/τ).
    """

    def __init__(self, rng: np.random.Generator, bias_rps: float | None = None,
                 noise_rps: float = 0.004, walk_rps_per_sqrt_s: float = 0.0002,
                 bias_tau_s: float = 3600.0) -> None:
        self.rng = rng
        self.bias = rng.normal(0.0, 0.004) if bias_rps is None else bias_rps
        self.turn_on_bias = self.bias
        self.noise = noise_rps
        self.walk = walk_rps_per_sqrt_s
        self.bias_tau_s = bias_tau_s
        self.wander_sigma = walk_rps_per_sqrt_s * math.sqrt(bias_tau_s / 2)  # steady state

    def sample(self, dt: float, true_rate_rps: float) -> float:
        phi = math.exp(-max(dt, 0.0) / self.bias_tau_s)
        self.bias = (self.turn_on_bias + (self.bias - self.turn_on_bias) * phi
                     + self.wander_sigma * math.sqrt(1.0 - phi * phi)
                     * self.rng.standard_normal())
        return true_rate_rps + self.bias + self.noise * self.rng.standard_normal()


class WheelEncoders:
    """Quadrature counts of the left/right wheels (cumulative, with a little slip)."""

    def __init__(self, rng: np.random.Generator, wheel_radius_m: float, ticks_per_rev: int,
                 slip: float = 0.01) -> None:
        self.rng = rng
        self.ticks_per_m = ticks_per_rev / (2 * math.pi * wheel_radius_m)
        self.slip = slip
        self._acc = [0.0, 0.0]

    def step(self, dt: float, v_left: float, v_right: float) -> tuple[int, int]:
        for i, v in enumerate((v_left, v_right)):
            self._acc[i] += v * dt * self.ticks_per_m * (1 + self.slip * self.rng.standard_normal())
        return int(math.floor(self._acc[0])), int(math.floor(self._acc[1]))


class TurnSlip:
    """Skid-steer wheels scrub when the base turns (seed 003 §2.2: slip on turns is
    what makes wheel odometry drift): the body turns by a fraction (1 − slip) of
    what the wheel speeds say. The slip grows with the turn rate,
    slip = gain·|ω| + an Ornstein-Uhlenbeck wander (σ·|ω|/ω_ref, time constant
    tau_s), clipped to [0, 0.5]; driving straight it is nil."""

    def __init__(self, rng: np.random.Generator, gain_per_rps: float = 0.06,
                 sigma: float = 0.02, ref_rps: float = 0.35, tau_s: float = 3.0) -> None:
        self.rng = rng
        self.gain = gain_per_rps
        self.sigma = sigma
        self.ref = ref_rps
        self.tau = tau_s
        self._wander = 0.0

    def step(self, dt: float, omega_rps: float) -> float:
        a = math.exp(-max(dt, 0.0) / self.tau)
        self._wander = a * self._wander + math.sqrt(1 - a * a) * self.rng.standard_normal()
        turn = abs(omega_rps)
        slip = self.gain * turn + self.sigma * (turn / self.ref) * self._wander
        return min(max(slip, 0.0), 0.5)
