"""Four-wheel independent steering (4WS) kinematics — seed 004 §2.1, Figs. 1–3.

Conventions (seed §2.1): body frame X along the chassis' centre line, Y to the
left, origin at the chassis centre; angles positive anticlockwise. The wheels
sit at (±L/2, ±W/2) — L the wheelbase, W the track — in the order
front-left, front-right, rear-left, rear-right.

1. Two-wheel (bicycle) model, Fig. 1: the four wheels collapse onto the centre
   line, a front wheel steered by δf and a rear wheel by δr. With the forward
   speed vx of the centre the body twist is

       ω  = vx (tan δf − tan δr) / L,     vy = vx (tan δf + tan δr) / 2,

   the centre's speed V = √(vx² + vy²) and its turning radius R = V / |ω|.
2. Instantaneous centre of rotation (ICR), Figs. 1–2: (−vy/ω, vx/ω) in the body
   frame. Each wheel i at (xi, yi) moves with (vx − ω yi, vy + ω xi): its
   steering angle is the direction of that vector, its speed the norm, i.e. its
   distance to the ICR times |ω| — so the inner wheels run slower and the outer
   wheels need smaller steering angles (seed, after eq. for the four speeds).
3. Limits, Fig. 2: every wheel's steering angle |δi| ≤ δmax; at the limit the
   centre follows the minimum turning radius (:func:`min_turn_radius`).
4. Discrete pose update, Fig. 3: between samples k and k+1 the input is held,
   so the centre runs on an arc about O with central angle Δθ = ω T; the exact
   arc displacement is used (:func:`integrate_pose`).

Modes the base allows: FRONT (Ackermann-like, δr = 0), COUNTER (counter-phase,
δr = −δf: the tightest arc), CRAB (in-phase, δr = δf: translation without
rotation) and PIVOT (turn in place: every wheel tangent to a circle about the
centre, which needs the servo travel ``pivot_steer_rad`` beyond δmax).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "FwsGeometry", "Mode", "Twist", "WheelCommand", "bicycle_to_twist", "body_twist", "icr",
    "integrate_pose", "limit_twist", "min_turn_radius", "mode_twist", "realise",
    "select_mode", "twist_to_bicycle", "wheel_commands",
]

WHEELS = ("front_left", "front_right", "rear_left", "rear_right")


@dataclass(frozen=True)
class FwsGeometry:
    """The base: wheelbase L and track W in metres, the steering limit δmax for
    driving on arcs, the servo travel (≥ the pivot angle atan(L/W)) and the
    wheels' top speed."""

    wheelbase_m: float = 0.60
    track_m: float = 0.50
    max_steer_rad: float = math.radians(35.0)
    servo_range_rad: float = math.radians(60.0)
    max_wheel_speed_mps: float = 1.5

    def __post_init__(self) -> None:
        if not (self.wheelbase_m > 0 and self.track_m > 0 and self.max_wheel_speed_mps > 0):
            raise ValueError("wheelbase_m, track_m and max_wheel_speed_mps must be > 0")
        if not 0 < self.max_steer_rad < math.pi / 2:
            raise ValueError("max_steer_rad must lie in (0, π/2)")
        if self.servo_range_rad < self.max_steer_rad:
            raise ValueError("servo_range_rad must be at least max_steer_rad")

    @property
    def wheel_xy(self) -> np.ndarray:
        """4 × 2 wheel positions (x, y) in the body frame, FL, FR, RL, RR."""
        a, b = self.wheelbase_m / 2, self.track_m / 2
        return np.array([[a, b], [a, -b], [-a, b], [-a, -b]])

    @property
    def pivot_steer_rad(self) -> float:
        """|steering angle| of every wheel when turning in place."""
        return math.atan2(self.wheelbase_m, self.track_m)


class Mode(enum.Enum):
    FRONT = "front"  # Ackermann-like: rear wheels straight
    COUNTER = "counter"  # counter-phase: δr = −δf, ICR on the lateral axis
    CRAB = "crab"  # in-phase: δr = δf, no rotation
    PIVOT = "pivot"  # turn in place about the centre


@dataclass(frozen=True)
class Twist:
    """Body-frame velocity of the chassis centre: vx forward, vy left (m/s),
    omega yaw rate (rad/s, anticlockwise positive)."""

    vx: float
    vy: float = 0.0
    omega: float = 0.0

    def as_array(self) -> np.ndarray:
        return np.array([self.vx, self.vy, self.omega])


@dataclass(frozen=True)
class WheelCommand:
    """Per-wheel steering angle (rad, in [−π/2, π/2]) and signed rolling speed
    (m/s), in the order FL, FR, RL, RR."""

    angles_rad: tuple[float, float, float, float]
    speeds_mps: tuple[float, float, float, float]


# ---- bicycle model (Fig. 1) --------------------------------------------------------


def bicycle_to_twist(geom: FwsGeometry, vx: float, delta_f: float, delta_r: float) -> Twist:
    """Twist of the two-wheel model with front/rear steering (item 1 above)."""
    tf, tr = math.tan(delta_f), math.tan(delta_r)
    return Twist(vx, vx * (tf + tr) / 2.0, vx * (tf - tr) / geom.wheelbase_m)


def twist_to_bicycle(geom: FwsGeometry, twist: Twist) -> tuple[float, float]:
    """(δf, δr) of the two-wheel model for a twist with vx ≠ 0: the directions
    of the velocity at the front and rear axle centres."""
    if abs(twist.vx) < 1e-12:
        raise ValueError("the bicycle model needs vx ≠ 0 (use Mode.PIVOT or CRAB sideways)")
    half = geom.wheelbase_m / 2
    return (
        math.atan((twist.vy + twist.omega * half) / twist.vx),
        math.atan((twist.vy - twist.omega * half) / twist.vx),
    )


def mode_twist(geom: FwsGeometry, mode: Mode, speed: float, steer: float = 0.0) -> Twist:
    """The twist of a driving mode. ``speed``: vx (m/s) for FRONT, COUNTER and
    CRAB, the yaw rate (rad/s) for PIVOT; ``steer``: the bicycle angle δf (rad)."""
    if mode is Mode.FRONT:
        return bicycle_to_twist(geom, speed, steer, 0.0)
    if mode is Mode.COUNTER:
        return bicycle_to_twist(geom, speed, steer, -steer)
    if mode is Mode.CRAB:
        return bicycle_to_twist(geom, speed, steer, steer)
    if mode is Mode.PIVOT:
        return Twist(0.0, 0.0, speed)
    raise ValueError(f"unknown mode {mode!r}")


# ---- ICR and the four wheels (Figs. 1–2) ---------------------------------------------


def icr(twist: Twist) -> tuple[float, float] | None:
    """The instantaneous centre of rotation in the body frame; None when the
    base translates (ω = 0)."""
    if abs(twist.omega) < 1e-12:
        return None
    return (-twist.vy / twist.omega, twist.vx / twist.omega)


def wheel_commands(geom: FwsGeometry, twist: Twist, hold=None) -> WheelCommand:
    """The four wheels' steering angles and speeds for a body twist (item 2).

    Angles are folded into [−π/2, π/2] with a negative speed when the wheel's
    velocity points backwards. A wheel at rest keeps the angle in ``hold``
    (its previous angle) or 0. Raises ValueError when an angle exceeds the
    servo travel; the δmax limit for arcs is checked by :func:`limit_twist`.
    Plain floats over the four wheels: the board runs this every sample.
    """
    angles, speeds = [], []
    for i, (x, y) in enumerate(_wheel_xy(geom)):
        ux, uy = twist.vx - twist.omega * y, twist.vy + twist.omega * x
        speed = math.hypot(ux, uy)
        ang = math.atan2(uy, ux)
        if abs(ang) > math.pi / 2 + 1e-12:
            ang -= math.copysign(math.pi, ang)
            speed = -speed
        if abs(speed) < 1e-12:
            ang = 0.0 if hold is None else float(hold[i])
        if abs(ang) > geom.servo_range_rad + 1e-9:
            raise ValueError(
                f"{WHEELS[i]} wheel needs {math.degrees(ang):.1f}°, beyond the servo "
                f"travel ±{math.degrees(geom.servo_range_rad):.1f}°"
            )
        angles.append(float(ang))
        speeds.append(float(speed))
    return WheelCommand(tuple(angles), tuple(speeds))


def _wheel_xy(geom: FwsGeometry) -> tuple[tuple[float, float], ...]:
    a, b = geom.wheelbase_m / 2, geom.track_m / 2
    return ((a, b), (a, -b), (-a, b), (-a, -b))


def body_twist(geom: FwsGeometry, cmd: WheelCommand) -> tuple[Twist, float]:
    """The body twist that best explains four wheel commands (least squares over
    the eight rigid-body equations vxi = vx − ω yi, vyi = vy + ω xi) and the
    RMS wheel slip (m/s) it leaves: 0 for a consistent command.

    The wheels sit symmetrically about the centre (Σxi = Σyi = Σxi·yi = 0), so
    the normal equations are diagonal: vx and vy are the means of the wheels'
    velocity components and ω = Σ(xi·vyi − yi·vxi) / Σ(xi² + yi²)."""
    a, sp = cmd.angles_rad, cmd.speeds_mps
    if len(a) != 4 or len(sp) != 4 or not all(math.isfinite(v) for v in (*a, *sp)):
        raise ValueError("a wheel command needs four finite angles and four finite speeds")
    xy = _wheel_xy(geom)
    bx = [float(s) * math.cos(t) for s, t in zip(sp, a, strict=True)]
    by = [float(s) * math.sin(t) for s, t in zip(sp, a, strict=True)]
    vx, vy = sum(bx) / 4.0, sum(by) / 4.0
    om = (sum(x * v for (x, _), v in zip(xy, by, strict=True))
          - sum(y * u for (_, y), u in zip(xy, bx, strict=True))) \
        / sum(x * x + y * y for x, y in xy)
    res = sum((vx - om * y - u) ** 2 + (vy + om * x - v) ** 2
              for (x, y), u, v in zip(xy, bx, by, strict=True))
    return Twist(vx, vy, om), math.sqrt(res / 8.0)


# ---- limits (Fig. 2) ------------------------------------------------------------------


def min_turn_radius(geom: FwsGeometry, mode: Mode = Mode.COUNTER) -> float:
    """Radius of the centre's tightest arc with every wheel within δmax.

    COUNTER: the ICR lies on the lateral axis at y = W/2 + (L/2)/tan δmax (the
    inner wheels reach δmax first), and that is the radius. FRONT: the ICR lies
    on the rear axle line at y = W/2 + L/tan δmax; the centre is L/2 ahead of it.
    PIVOT: 0. CRAB never turns (∞)."""
    t = math.tan(geom.max_steer_rad)
    half_w = geom.track_m / 2
    if mode is Mode.COUNTER:
        return half_w + geom.wheelbase_m / 2 / t
    if mode is Mode.FRONT:
        return math.hypot(geom.wheelbase_m / 2, half_w + geom.wheelbase_m / t)
    if mode is Mode.PIVOT:
        return 0.0
    return math.inf


def limit_twist(geom: FwsGeometry, twist: Twist) -> Twist:
    """The twist scaled so that no wheel exceeds its top speed and, for a
    moving base (vx ≠ 0), the turn is no tighter than δmax allows on any
    wheel (ω clipped towards 0, keeping vx and the crab component).

    With σ = sign(vx) and T = tan δmax, wheel i stays within δmax of the
    driving direction while −T·σ(vx − ω yi) ≤ vy + ω xi ≤ T·σ(vx − ω yi):
    two inequalities linear in ω per wheel (which also keep it rolling
    forwards), so the allowed ω form one interval and ω is clipped into it
    (to 0 when even ω = 0 is outside: a crab angle past δmax)."""
    vx, vy, om = twist.vx, twist.vy, twist.omega
    xy = _wheel_xy(geom)
    if abs(vx) > 1e-9:
        sg, tn = math.copysign(1.0, vx), math.tan(geom.max_steer_rad)
        lo, hi = -math.inf, math.inf
        for x, y in xy:
            # a·ω ≤ b for each side: vy + ω x ≤ T σ (vx − ω y), −(vy + ω x) ≤ T σ (vx − ω y)
            for k in (1.0, -1.0):
                ca, cb = k * x + tn * sg * y, tn * sg * vx - k * vy
                if abs(ca) < 1e-12:
                    if cb < 0:
                        lo, hi = 0.0, 0.0
                elif ca > 0:
                    hi = min(hi, cb / ca)
                else:
                    lo = max(lo, cb / ca)
        if lo > hi or lo > 0 or hi < 0:
            om = 0.0
        else:
            om = min(max(om, lo), hi)
    top = max(math.hypot(vx - om * y, vy + om * x) for x, y in xy)
    k = min(1.0, geom.max_wheel_speed_mps / top) if top > 0 else 1.0
    return Twist(vx * k, vy * k, om * k)


# ---- choosing the steering mode -----------------------------------------------------------

FRONT_MIN_SPEED_MPS = 0.35  # front steer only when driving at least this fast
FRONT_RADIUS_FACTOR = 2.0  # ... on arcs at least this × its minimum turning radius


def select_mode(geom: FwsGeometry, twist: Twist) -> Mode:
    """The steering mode for a body twist: PIVOT for a turn without travel,
    CRAB for travel without turning (a sideways component, as in a docking
    correction), FRONT (Ackermann-like: rear wheels straight, the steadier
    choice at speed) for gentle arcs at speed — the arc at least
    FRONT_RADIUS_FACTOR × the front-steer minimum radius, so the front wheels
    stay far from δmax — and COUNTER (the tightest arcs) otherwise."""
    moving = math.hypot(twist.vx, twist.vy) > 1e-3
    if not moving:
        return Mode.PIVOT
    if abs(twist.omega) < 1e-6:
        return Mode.CRAB if abs(twist.vy) > 1e-3 else Mode.COUNTER
    radius = abs(twist.vx / twist.omega)
    if (abs(twist.vx) >= FRONT_MIN_SPEED_MPS and abs(twist.vy) < 1e-3
            and radius >= FRONT_RADIUS_FACTOR * min_turn_radius(geom, Mode.FRONT)):
        return Mode.FRONT
    return Mode.COUNTER


def realise(geom: FwsGeometry, mode: Mode, twist: Twist) -> Twist:
    """The twist the base drives for a commanded (vx, ω) (and vy for CRAB) in
    ``mode``: FRONT keeps the rear axle's centre from sliding sideways, so the
    chassis centre gets vy = ω·L/2 (its ICR on the rear axle line, Fig. 1 with
    δr = 0); COUNTER and PIVOT have vy = 0; CRAB has ω = 0."""
    if mode is Mode.FRONT:
        return Twist(twist.vx, twist.omega * geom.wheelbase_m / 2, twist.omega)
    if mode is Mode.CRAB:
        return Twist(twist.vx, twist.vy, 0.0)
    if mode is Mode.PIVOT:
        return Twist(0.0, 0.0, twist.omega)
    return Twist(twist.vx, 0.0, twist.omega)


# ---- discrete pose update (Fig. 3) ------------------------------------------------------


def integrate_pose(pose, twist: Twist, dt: float) -> tuple[float, float, float]:
    """Pose (x, y, θ) after holding ``twist`` for dt seconds: the centre moves
    on an arc of central angle Δθ = ω dt about the ICR (Fig. 3); a straight
    line when ω = 0."""
    x, y, th = float(pose[0]), float(pose[1]), float(pose[2])
    dth = twist.omega * dt
    if abs(dth) < 1e-9:
        bx, by = twist.vx * dt, twist.vy * dt
    else:
        s, c1 = math.sin(dth), 1.0 - math.cos(dth)
        bx = (twist.vx * s - twist.vy * c1) / twist.omega
        by = (twist.vx * c1 + twist.vy * s) / twist.omega
    c, s = math.cos(th), math.sin(th)
    th2 = math.atan2(math.sin(th + dth), math.cos(th + dth))
    return (x + c * bx - s * by, y + s * bx + c * by, th2)
