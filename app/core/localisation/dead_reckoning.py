"""Dead reckoning from wheel encoders (seed 002 §2.2, Fig. 4; seed 003 §2.1).

Encoder pulses to wheel arcs (seed 002 eq. 3):

    Δs_R = C·Δ_R + ε_R,   Δs_L = C·Δ_L + ε_L,   C = πD / (N·M)

with D the drive-wheel diameter, N the gear ratio and M the motor's pulses
per revolution. The motion centre E halfway between the wheels moves
(seed 002 eq. 2)

    Δs = (Δs_R + Δs_L) / 2,   Δθ = (Δs_R − Δs_L) / W

where, for a skid-steer base, W is the *effective* track: the geometric
track times a skid factor measured once by turning on the spot (the wheels
scrub, so the base turns less than a two-wheel model says). The pose is
integrated at the mid-angle (seed 002 eq. 1; seed 003 eqs. 1–2 in velocity
form, P_k = P_{k−1} + Ṗ_{k−1} Δt):

    x_k = x_{k−1} + Δs cos(θ_{k−1} + Δθ/2)
    y_k = y_{k−1} + Δs sin(θ_{k−1} + Δθ/2)
    θ_k = θ_{k−1} + Δθ
"""

from __future__ import annotations

import math
from dataclasses import dataclass


def pulse_to_arc_m(wheel_diameter_m: float, gear_ratio: float, pulses_per_rev: float) -> float:
    """C = πD / (N·M), metres of wheel arc per encoder pulse (seed 002 eq. 3)."""
    if wheel_diameter_m <= 0 or gear_ratio <= 0 or pulses_per_rev <= 0:
        raise ValueError("wheel diameter, gear ratio and pulses per revolution must be positive")
    return math.pi * wheel_diameter_m / (gear_ratio * pulses_per_rev)


def arcs_to_motion(ds_left_m: float, ds_right_m: float, track_m: float) -> tuple[float, float]:
    """(Δs, Δθ) of the motion centre from the two wheel arcs (seed 002 eq. 2)."""
    return (ds_right_m + ds_left_m) / 2.0, (ds_right_m - ds_left_m) / track_m


def integrate(pose: tuple[float, float, float], ds_m: float,
              dtheta_rad: float) -> tuple[float, float, float]:
    """One dead-reckoning step at the mid-angle (seed 002 eq. 1)."""
    x, y, th = pose
    mid = th + dtheta_rad / 2.0
    th2 = (th + dtheta_rad + math.pi) % (2 * math.pi) - math.pi
    return x + ds_m * math.cos(mid), y + ds_m * math.sin(mid), th2


def _wrap_counter(d: int, bits: int) -> int:
    half = 1 << (bits - 1)
    return ((d + half) % (1 << bits)) - half


@dataclass
class DeadReckoning:
    """Pose from cumulative encoder counts (a counter may wrap at ``counter_bits``)."""

    arc_per_pulse_m: float
    track_m: float  # effective track (geometric × skid factor)
    x: float = 0.0
    y: float = 0.0
    theta: float = 0.0
    counter_bits: int = 32

    def __post_init__(self) -> None:
        self._last: tuple[int, int] | None = None

    @property
    def pose(self) -> tuple[float, float, float]:
        return self.x, self.y, self.theta

    def update(self, count_left: int, count_right: int) -> tuple[float, float]:
        """Feed the cumulative counts; returns this step's (Δs, Δθ)."""
        if self._last is None:
            self._last = (count_left, count_right)
            return 0.0, 0.0
        dl = _wrap_counter(count_left - self._last[0], self.counter_bits)
        dr = _wrap_counter(count_right - self._last[1], self.counter_bits)
        self._last = (count_left, count_right)
        ds, dth = arcs_to_motion(dl * self.arc_per_pulse_m, dr * self.arc_per_pulse_m,
                                 self.track_m)
        self.x, self.y, self.theta = integrate(self.pose, ds, dth)
        return ds, dth
