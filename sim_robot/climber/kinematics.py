"""The magnetic wall climber's body: four-wheel differential drive on a
vertical steel wall, with the slip that makes its wheel odometry drift
(seed 003 §1, §2.2, Tables 1 and 3).

Frame: the unrolled wall (see app/core/planner/coverage/wall.py): x round the
tank from the shell's seam, y up; heading θ from +x, counter-clockwise.
Gravity pulls towards −y.

Commands (v, ω) are limited as in Table 3 (|v| ≤ 0.15 m/s, |ω| ≤ 0.5 rad/s,
|dv/dt| ≤ 0.5 m/s², |dω/dt| ≤ 3.5 rad/s²) and turned into wheel speeds
v_l,r = v ∓ ω·track/2 — what the encoders count. The body then moves less
than the wheels say:

- skid-steer turning slip: the body turns by (1 − s_turn)·ω, s_turn growing
  with the turn rate (seed 003 §2.2: "the wheels slip when it turns");
- gravity: climbing, it slips back by s_up·sin θ of its speed; descending it
  overruns by s_down·|sin θ|;
- creep: the magnets hold the body against the wall but it creeps down by
  creep·|cos θ|·(|v| + track/2·|ω|) — more when turning, when the wheels
  scrub sideways;
- each slip factor varies a little from turn to turn (seeded noise).

Given ``contact`` (:meth:`.contact.WallContact.depth`: how far the body's
footprint at a pose reaches past the wall's top or bottom or into an
obstacle), a step goes only as far as the footprint stays clear (bisected on
the step's fraction): the body stops at the boundary and its wheels stall
there (the encoders and the gyro see only the motion made). The creep is the
one part of a step that the boundary takes up instead: a body resting on the
wall's bottom edge or on an obstacle below it does not creep into it, it
drives on along it (without that, a level body on the bottom edge would stall
on any motion at all). Each contact is
recorded (``contacts``: what, where, when; once per ``CONTACT_REARM_S`` per
thing, as the patrol robot's world records collisions) — ground truth for
evaluation; the board reports a contact in its flags (:mod:`.mcu`).

The defaults put the yaw error of wheel odometry at the end of a 90° turn at
0.35 rad/s near seed 003 Table 2's "before fusion" maxima (12.8–14.4°, run
means 6.0–8.8°, 7.03° over the ten runs).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

CONTACT_REARM_S = 2.0  # touching the same thing again within this is the same contact


@dataclass(frozen=True)
class ClimberParams:
    """Table 1 (body 288 × 260 mm, 6.5 kg) and Table 3 (limits) of seed 003."""

    length_m: float = 0.288
    width_m: float = 0.260
    mass_kg: float = 6.5
    track_m: float = 0.22
    wheel_radius_m: float = 0.03
    ticks_per_rev: int = 1024
    v_max_mps: float = 0.15
    omega_max_rps: float = 0.5
    accel_mps2: float = 0.5
    alpha_rps2: float = 3.5
    s_turn: float = 0.22  # turning slip at |ω| = ω_max
    s_up: float = 0.04
    s_down: float = 0.02
    creep: float = 0.01
    slip_jitter: float = 0.15  # relative spread of the slip factors


@dataclass
class ClimberState:
    """True pose on the wall and the speeds the wheels are turning at."""

    x_m: float = 0.0
    y_m: float = 0.0
    theta_rad: float = math.pi / 2  # facing up
    v_mps: float = 0.0
    omega_rps: float = 0.0


def _toward(cur: float, target: float, step: float) -> float:
    return cur + max(-step, min(step, target - cur))


class ClimberBody:
    """Steps the true pose; reports the wheel speeds (for the encoders) and
    the true yaw rate (for the IMU)."""

    def __init__(
        self,
        params: ClimberParams | None = None,
        state: ClimberState | None = None,
        circumference_m: float | None = None,
        seed: int = 0,
        height_m: float | None = None,
        contact: Callable[[float, float, float], tuple[float, str]] | None = None,
    ) -> None:
        self.p = params or ClimberParams()
        self.s = state or ClimberState()
        self.circumference_m = circumference_m
        self.height_m = height_m  # the body stops at the wall's top and bottom edges
        self.rng = np.random.default_rng(seed)
        self._jitter = self._draw()
        self._turning = False
        self.v_true_mps = 0.0  # the body's own forward speed (slip included)
        self.contact = contact
        self.t_s = 0.0  # the body's own time (the sum of its steps)
        self.touching = ""  # what the last step was stopped by ("" none)
        self.contacts: list[dict] = []  # each contact: t_s, what, x_m, y_m (truth)
        self._last_touch: dict[str, float] = {}

    def _draw(self) -> float:
        return float(max(0.0, 1.0 + self.p.slip_jitter * self.rng.standard_normal()))

    def limit(self, v_cmd: float, omega_cmd: float, dt: float) -> tuple[float, float]:
        """The wheel speeds reachable this step (Table 3)."""
        p = self.p
        v_cmd = max(-p.v_max_mps, min(p.v_max_mps, v_cmd))
        omega_cmd = max(-p.omega_max_rps, min(p.omega_max_rps, omega_cmd))
        return _toward(self.s.v_mps, v_cmd, p.accel_mps2 * dt), _toward(
            self.s.omega_rps, omega_cmd, p.alpha_rps2 * dt
        )

    def step(self, v_cmd: float, omega_cmd: float, dt: float) -> tuple[float, float, float]:
        """Advance dt seconds. Returns (v_left, v_right, true yaw rate)."""
        if dt <= 0:
            return 0.0, 0.0, 0.0
        p, s = self.p, self.s
        s.v_mps, s.omega_rps = self.limit(v_cmd, omega_cmd, dt)
        turning = abs(s.omega_rps) > 0.05
        if turning and not self._turning:
            self._jitter = self._draw()  # each turn slips a little differently
        self._turning = turning
        j = self._jitter
        slip_turn = min(0.9, p.s_turn * j * abs(s.omega_rps) / p.omega_max_rps)
        omega_true = (1.0 - slip_turn) * s.omega_rps
        sin_t = math.sin(s.theta_rad)
        heading_up = s.v_mps * sin_t  # > 0: climbing
        if heading_up > 0:
            v_true = s.v_mps * (1.0 - p.s_up * j * sin_t)
        else:
            v_true = s.v_mps * (1.0 + p.s_down * j * abs(sin_t))
        creep = (
            p.creep
            * j
            * abs(math.cos(s.theta_rad))
            * (abs(s.v_mps) + p.track_m / 2 * abs(s.omega_rps))
        )
        mid = s.theta_rad + omega_true * dt / 2
        dx = v_true * math.cos(mid) * dt
        dy = v_true * math.sin(mid) * dt - creep * dt
        dth = omega_true * dt
        f = 1.0
        if self.contact is not None:
            f, what = self._free_fraction(dx, dy, dth)
            if f < 1.0 and creep > 0.0:  # resting on what is below: it holds the creep
                f_held, what_held = self._free_fraction(dx, dy + creep * dt, dth)
                if f_held > f:
                    f, what, dy = f_held, what_held, dy + creep * dt
            self._record(f, what)
        self.t_s += dt
        half = p.track_m / 2
        vl, vr = s.v_mps - half * s.omega_rps, s.v_mps + half * s.omega_rps
        if f < 1.0:  # stopped at the boundary: the wheels stall, the motors start again
            vl, vr, v_true, omega_true = f * vl, f * vr, f * v_true, f * omega_true
            s.v_mps = s.omega_rps = 0.0
        self.v_true_mps = v_true
        s.x_m += f * dx
        s.y_m += f * dy
        s.theta_rad = (s.theta_rad + f * dth + math.pi) % (2 * math.pi) - math.pi
        if self.circumference_m:
            s.x_m %= self.circumference_m
        if self.height_m is not None:
            s.y_m = min(self.height_m, max(0.0, s.y_m))
        return vl, vr, omega_true

    def _free_fraction(self, dx: float, dy: float, dth: float) -> tuple[float, str]:
        """The share of the step (dx, dy, dθ) the body can make before its footprint
        reaches past the wall's edge or into an obstacle (further than it already
        does: a body started overlapping may move out), and what stops it ("")."""
        s, contact = self.s, self.contact
        x0, y0, th0 = s.x_m, s.y_m, s.theta_rad
        limit = max(0.0, contact(x0, y0, th0)[0]) + 1e-9
        depth, what = contact(x0 + dx, y0 + dy, th0 + dth)
        if depth <= limit:
            return 1.0, ""
        lo, hi = 0.0, 1.0
        for _ in range(10):  # to a thousandth of the step (< 0.01 mm at full speed)
            f = (lo + hi) / 2
            if contact(x0 + f * dx, y0 + f * dy, th0 + f * dth)[0] <= limit:
                lo = f
            else:
                hi = f
        return lo, what

    def _record(self, f: float, what: str) -> None:
        """Keep what stopped the step (``touching``) and record the contact."""
        if f >= 1.0:
            self.touching = ""
            return
        self.touching = what
        if self.t_s - self._last_touch.get(what, -math.inf) >= CONTACT_REARM_S:
            self.contacts.append({"t_s": round(self.t_s, 2), "what": what,
                                  "x_m": round(self.s.x_m, 3), "y_m": round(self.s.y_m, 3)})
        self._last_touch[what] = self.t_s
