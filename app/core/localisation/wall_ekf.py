"""The wall climber's pose on a vertical steel wall: the odometry EKF of seed
003 (eqs. 4–13, :class:`.ekf.OdometryEkf`) with what a vertical wall adds —
gravity slip in the motion model, gravity as an absolute heading, and the
shell's weld seams as landmarks.

Frame: the unrolled wall, x round the tank, y up; θ from +x,
counter-clockwise; gravity along −y.

State (eq. 5 extended): X = [x, y, θ, v_x, v_y, ω_z, k_up, k_down, k_creep, b_x, b_y, b_g]ᵀ.
v_x is the speed the wheels turn at (what the encoders measure); the body
moves less or more than that under gravity, by coefficients the filter
learns from the landmarks (random walks, prior 0):

- climbing (v_x sin θ > 0) it slips back:  v_eff = v_x (1 − k_up |sin θ|);
- descending it overruns:                  v_eff = v_x (1 + k_down |sin θ|);
- crossing the wall it creeps down at k_creep |cos θ| (|v_x| + b/2 |ω_z|),
  more when turning (the wheels scrub), b the track.

Motion (eq. 6 with v_eff for v_x, and the creep):

    x_k = x + Δt (cos θ v_eff − sin θ v_y)
    y_k = y + Δt (sin θ v_eff + cos θ v_y − k_creep |cos θ| (|v_x| + b/2 |ω_z|))
    θ_k = θ + Δt ω_z

Its Jacobian (eq. 7) is written out in :meth:`WallEkf.jacobian`.

Measurements (eqs. 10–13, each linear in the state):

- encoders and gyro as in :class:`.ekf.OdometryEkf`;
- gravity heading: on a vertical wall the accelerometer's specific force in
  the body frame is (a_fwd + g sin θ + b_x, v ω + g cos θ + b_y), so
  θ_g = atan2(f_x − a_fwd, f_y − v ω) — an absolute heading, no yaw drift (the
  board removes a_fwd, the wheels' acceleration, before it sends θ_g). The
  accelerometer's bias (b_x, b_y) turns it by

      θ_g ≈ θ + (b_x cos θ − b_y sin θ) / g,

  a heading error that changes sign with the direction of travel: climbing
  (θ = 90°) it is −b_y/g, descending +b_y/g, so the true path leans the same
  way on the way up and on the way down and vertical lanes drift sideways
  lane after lane (1 mg of bias: ≈ 1 cm per 10 m lane). The bias is therefore
  two states, random walks from a prior of 0; the gyro, which sees the turn
  between an up lane and a down lane, tells the two readings' difference
  (2 b_y/g) from a true turn, and the bias becomes observable;
- the rim of a manhole or nozzle under the camera (:meth:`WallEkf.rim_seen`):
  the image gives the offsets from its centre to the rim's nearest point, o,
  and to the rim's centre, both in the body frame; with the map's radius r
  the centre seen is m = o + r n̂ (n̂ the unit vector from the rim point to
  the centre), and the measurement is that centre in the body frame,

      h(X) = R(θ)ᵀ (C − c),   c = (x + L cos θ, y + L sin θ),

  C the mapped centre, L the camera's lead: x, y and θ, on the side of the
  rim the camera is truly on. (A range alone, ‖c + R(θ) o − C‖ = r, is met
  by every believed point whose rim point lies on the circle: the point a
  rim's width away across the opening, or one slid round it; a belief 0.4 m
  low above a manhole was pulled to the wrong side, 0.6 m low, and held
  there.) Its Jacobian is written out in :meth:`WallEkf.rim_model`;
- a weld seam under the camera (:meth:`WallEkf.seam_seen`): the nearest
  mapped seam of the seen direction (gated) gives y (a girth seam) or x (a
  vertical seam) of the camera point, and the seam's direction in the image
  gives θ.

The gyro reads ω_z + b_g: its bias b_g is a state too (a random walk from a
prior of the gyro's turn-on bias, :class:`.ekf.OdometryEkf`'s optional
seventh state), learnt wherever the encoders and the gravity heading hold the
heading still. Without it a gyro bias the caller's standstill mean missed is a
drift the filter does not model: the gravity heading holds it back with an
innovation of one sign that the accelerometer's bias states take up, and the
heading is believed to 1.5 mrad while it is 15–90 mrad off
(docs/climber.md, "The lean of the first lanes: the gyro's bias").

The encoders and gyro cannot see a slip (the wheels turn as commanded, the
body does not turn); each landmark fix corrects the position and, through
the covariance the motion model built up, the slip coefficient that caused
the error, so the next stretch drifts less.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._ekf_kernels import symmetrise_positive_definite
from .ekf import TH, VX, VY, WZ, EkfNoise, OdometryEkf, X, Y

K_UP, K_DOWN, K_CREEP = 6, 7, 8
B_X, B_Y = 9, 10  # the accelerometer's bias along the body's x and y (m/s²)
B_G = 11  # the gyro's bias (rad/s) left after the caller's standstill mean
N_STATE = 12
G_MPS2 = 9.81


@dataclass(frozen=True)
class WallNoise:
    slip_prior: float = 0.03  # σ of each slip coefficient at the start
    slip_walk: float = 0.002  # their random walk per √s (they vary from turn to turn)
    # and per √m of the farther wheel's arc (off by default): a slip that changes as the
    # body moves over new paint, rust and welds, not while it stands (docs/climber.md,
    # "The slip states' walk per metre, tried headless")
    slip_walk_per_m: float = 0.0
    accel_bias_prior: float = 0.05  # σ of each accelerometer bias at the start (m/s², 5 mg)
    accel_bias_walk: float = 1e-5  # their random walk (m/s² per √s: temperature drift)
    gyro_bias_prior: float = 0.005  # σ of the gyro's bias at the start (rad/s, its turn-on bias)
    gyro_bias_walk: float = 0.0002  # its random walk (rad/s per √s)
    gravity_heading_rad: float = math.radians(0.3)  # σ of one accelerometer heading
    gravity_gate: float = 5.0  # innovations beyond this many σ are dropped (jolts)
    gravity_reset_after: int = 20  # ...unless this many in a row disagree: the belief is wrong
    seam_m: float = 0.01  # σ of a seam's position under the camera
    seam_angle_rad: float = math.radians(1.0)  # σ of its direction in the image
    seam_gate_m: float = 1.0  # farthest mapped seam taken for the one seen
    seam_sigmas: float = 5.0  # a seam fix further than this many σ from the belief is dropped
    seam_reset_after: int = 20  # ...unless this many in a row disagree: the belief is wrong
    seam_span_sigmas: float = 3.0  # a seam's ends are stretched by this many σ along it
    rim_m: float = 0.005  # σ of a rim point's position under the camera (along the normal)
    rim_angle_rad: float = 0.02  # σ of the normal's direction in the image (r σ across it)
    rim_radius_m: float = 0.004  # a rim seen at a radius further than this from the map's is not it
    rim_gate_m: float = 0.3  # farthest mapped centre from where the belief puts the one seen


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi



def nearest_seam_offset(seams, horizontal: bool, cx: float, cy: float,
                        circ_m: float, span_margin_m: float = 0.0) -> float | None:
    """Signed offset (m) from the point (cx, cy) to the nearest mapped seam of the
    given direction that passes it (y for a girth seam, x round the tank for a
    vertical one, the short way across the wrap); None when no seam passes it.
    ``span_margin_m`` stretches each seam's ends: a point believed just past
    the end of the seam it truly sees (vertical seams end at the girth seams,
    staggered from course to course) still finds it, not the next seam round."""
    best = None
    for b in seams:
        if horizontal and b.y0_m == b.y1_m:
            lo, hi = sorted((b.x0_m, b.x1_m))
            inside = (hi - lo >= circ_m - 1e-6
                      or abs((cx - (lo + hi) / 2 + circ_m / 2) % circ_m - circ_m / 2)
                      <= (hi - lo) / 2 + span_margin_m)
            d = b.y0_m - cy if inside else None
        elif not horizontal and b.x0_m == b.x1_m:
            lo, hi = sorted((b.y0_m, b.y1_m))
            inside = lo - span_margin_m <= cy <= hi + span_margin_m
            d = (b.x0_m - cx + circ_m / 2) % circ_m - circ_m / 2 if inside else None
        else:
            d = None
        if d is not None and (best is None or abs(d) < abs(best)):
            best = d
    return best

class WallEkf(OdometryEkf):
    """Twelve-state EKF of a magnetic crawler on a vertical wall (see module)."""

    def __init__(self, x: float = 0.0, y: float = 0.0, theta: float = 0.0,
                 track_m: float = 0.22, noise: EkfNoise | None = None,
                 wall: WallNoise | None = None) -> None:
        super().__init__(x, y, theta, noise=noise or EkfNoise(), track_m=track_m)
        self.wall = wall or WallNoise()
        self.n = N_STATE
        self._x = np.concatenate([self._x[:6], np.zeros(N_STATE - 6)])
        p = np.zeros((N_STATE, N_STATE))
        p[:6, :6] = self._p[:6, :6]
        p[K_UP:B_X, K_UP:B_X] = np.eye(3) * self.wall.slip_prior**2
        p[B_X:B_G, B_X:B_G] = np.eye(2) * self.wall.accel_bias_prior**2
        p[B_G, B_G] = self.wall.gyro_bias_prior**2
        self._p = p
        self.rejected = {"gravity": 0, "seam": 0, "rim": 0}
        self.resets = {"gravity": 0, "seam": 0, "rim": 0}  # rejections ended by a reset
        self.repairs = 0  # times P was found not positive definite and mended
        self._gravity_out = 0  # consecutive gravity headings beyond the gate
        self.gravity_innov = 0.0  # the last gravity heading's innovation, rad (taken or not)
        self._seam_out = 0  # consecutive seam sightings beyond the innovation gate
        self._rim_out = 0  # consecutive rim sightings beyond the innovation gate

    @property
    def gravity_out(self) -> int:
        """Gravity headings refused in a row so far (0: the last one was taken)."""
        return self._gravity_out

    @property
    def slip(self) -> tuple[float, float, float]:
        """Learnt (k_up, k_down, k_creep)."""
        return float(self._x[K_UP]), float(self._x[K_DOWN]), float(self._x[K_CREEP])

    @property
    def gyro_bias(self) -> float:
        """Learnt gyro bias (rad/s), beyond what the caller removed."""
        return float(self._x[B_G])

    def update_imu_yaw_rate(self, omega_rps: float, sigma_rps: float | None = None
                            ) -> np.ndarray:
        """The gyro reads ω_z + b_g (H = [0 … 1 … 1], as :class:`.ekf.OdometryEkf`
        with its bias state)."""
        h = np.zeros((1, N_STATE))
        h[0, WZ] = 1.0
        h[0, B_G] = 1.0
        s = self.noise.gyro_yaw_rate_rps if sigma_rps is None else sigma_rps
        return self.update(np.array([omega_rps]), h, np.array([[s * s]]))

    @property
    def accel_bias(self) -> tuple[float, float]:
        """Learnt accelerometer bias (b_x, b_y), m/s²."""
        return float(self._x[B_X]), float(self._x[B_Y])

    def set_accel_bias(self, bias: tuple[float, float], sigma: float) -> None:
        """Start the bias states from a calibration (:mod:`.accel_calibration`):
        the value and its standard error, uncorrelated with the rest."""
        self._x[B_X:B_Y + 1] = bias
        self._p[B_X:B_Y + 1, :] = 0.0
        self._p[:, B_X:B_Y + 1] = 0.0
        self._p[B_X:B_Y + 1, B_X:B_Y + 1] = np.eye(2) * sigma**2

    def open_variance(self, k: int, sigma: float) -> None:
        """Raise state ``k``'s variance to at least σ² (its correlations kept in
        proportion): evidence outside the filter that the belief may be off
        (a contact, :mod:`.contact_fix`)."""
        var = self._p[k, k]
        if var >= sigma * sigma:
            return
        if var <= 0.0:
            self._p[k, k] = sigma * sigma
            return
        f = sigma / math.sqrt(var)
        self._p[k, :] *= f
        self._p[:, k] *= f

    # -- predict (eqs. 6–9) -------------------------------------------------------------
    def _terms(self, st: np.ndarray):
        th, vx, wz = st[TH], st[VX], st[WZ]
        c, s = math.cos(th), math.sin(th)
        a = abs(s)
        sg = 1.0 if s >= 0 else -1.0
        if vx * s > 0:  # climbing
            f, df_th, df_k = 1.0 - st[K_UP] * a, -st[K_UP] * sg * c, (-a, 0.0)
        else:
            f, df_th, df_k = 1.0 + st[K_DOWN] * a, st[K_DOWN] * sg * c, (0.0, a)
        g = abs(vx) + self.track_m / 2 * abs(wz)
        return c, s, f, df_th, df_k, g

    @staticmethod
    def _mid(state: np.ndarray, dt: float) -> np.ndarray:
        """The state with θ at the interval's middle, θ + ω dt/2: the chord of an
        arc driven at steady v and ω points there (eq. 6 takes the start's θ,
        which puts every turn's chord a quarter of its turn off)."""
        mid = state.copy()
        mid[TH] = state[TH] + state[WZ] * dt / 2
        return mid

    def motion(self, state: np.ndarray, dt: float) -> np.ndarray:  # type: ignore[override]
        c, s, f, _, _, g = self._terms(self._mid(state, dt))
        vx, vy = state[VX], state[VY]
        out = state.copy()
        v_eff = vx * f
        out[X] = state[X] + dt * (c * v_eff - s * vy)
        out[Y] = state[Y] + dt * (s * v_eff + c * vy - state[K_CREEP] * abs(c) * g)
        out[TH] = _wrap(state[TH] + dt * state[WZ])
        return out

    def jacobian(self, state: np.ndarray, dt: float) -> np.ndarray:  # type: ignore[override]
        c, s, f, df_th, df_k, g = self._terms(self._mid(state, dt))
        vx, vy, wz, kc = state[VX], state[VY], state[WZ], state[K_CREEP]
        v_eff = vx * f
        sc = 1.0 if c >= 0 else -1.0
        a = np.eye(N_STATE)  # the slip and bias states are random walks
        a[X, TH] = dt * (-s * v_eff + c * vx * df_th - c * vy)
        a[X, VX] = dt * c * f
        a[X, VY] = -dt * s
        a[X, K_UP] = dt * c * vx * df_k[0]
        a[X, K_DOWN] = dt * c * vx * df_k[1]
        a[Y, TH] = dt * (c * v_eff + s * vx * df_th - s * vy + kc * sc * s * g)
        a[Y, VX] = dt * (s * f - kc * abs(c) * (1.0 if vx >= 0 else -1.0))
        a[Y, VY] = dt * c
        a[Y, WZ] = -dt * kc * abs(c) * self.track_m / 2 * (1.0 if wz >= 0 else -1.0)
        a[Y, K_UP] = dt * s * vx * df_k[0]
        a[Y, K_DOWN] = dt * s * vx * df_k[1]
        a[Y, K_CREEP] = -dt * abs(c) * g
        # θ enters at the middle of the interval, θ + ω dt/2
        a[X, WZ] += a[X, TH] * dt / 2
        a[Y, WZ] += a[Y, TH] * dt / 2
        a[TH, WZ] = dt
        return a

    def process_noise(self, dt: float) -> np.ndarray:
        q = np.zeros((N_STATE, N_STATE))
        q[:6, :6] = OdometryEkf.process_noise(self, dt)[:6, :6]
        q[K_UP:B_X, K_UP:B_X] = np.eye(3) * self.wall.slip_walk**2 * dt
        q[B_X:B_G, B_X:B_G] = np.eye(2) * self.wall.accel_bias_walk**2 * dt
        q[B_G, B_G] = self.wall.gyro_bias_walk**2 * dt
        return q

    def advance(self, dt: float, ds_left_m: float, ds_right_m: float,
                gyro_rps: float | None = None, gyro_unseen_rps: float = 0.0) -> None:
        """:meth:`.ekf.OdometryEkf.advance`, the slip coefficients first walking by
        ``slip_walk_per_m`` per √m of this interval's farther wheel arc, max(|Δs_L|, |Δs_R|)
        = |Δs| + b/2 |Δθ|: the path the creep term scrubs (Q's slip block, eq. 9,
        proportional to the distance driven rather than to the time)."""
        walk = self.wall.slip_walk_per_m
        arc = max(abs(ds_left_m), abs(ds_right_m))
        if walk > 0.0 and arc > 0.0 and dt > 0:
            self._own_arrays()
            for k in (K_UP, K_DOWN, K_CREEP):
                self._p[k, k] += walk * walk * arc
        super().advance(dt, ds_left_m, ds_right_m, gyro_rps, gyro_unseen_rps)
        self._keep_covariance()

    def _keep_covariance(self) -> None:
        """P kept symmetric and positive definite. The multiplied-out Joseph form
        (``_ekf_kernels.update``) is symmetric only for a symmetric P, and its
        rounding's asymmetry grew
        tenfold every 50 000-150 000 steps through the link (1e-15 to 1e-12 in the
        tank's first 9000 s), where two runs' covariances later held negative
        variances and their beliefs ran away (docs/climber.md)."""
        if not symmetrise_positive_definite(self._p):  # P = (P + Pᵀ) / 2 in place
            self._repair()

    def _repair(self) -> None:
        """P back to the nearest positive-definite matrix, counted: its eigenvalues
        below a floor (1e-10 of the largest, and at least 1e-14) raised to it and
        the eigenvectors kept. Rounding alone can make P indefinite; a filter with
        a negative variance believes a measurement more than a certainty and its
        estimate runs away (docs/climber.md), so this is mended where it is seen."""
        p = self._p
        if not np.all(np.isfinite(p)):
            return  # nothing to mend it from
        w, v = np.linalg.eigh(p)
        floor = max(1e-10 * float(np.max(np.abs(w))), 1e-14)
        p[:, :] = (v * np.maximum(w, floor)) @ v.T
        p[:, :] = 0.5 * (p + p.T)
        self.repairs += 1

    def update(self, z: np.ndarray, h: np.ndarray, r: np.ndarray) -> np.ndarray:
        """Eqs. 10–13 as in :class:`.ekf.OdometryEkf`; the accelerometer's bias
        is then kept within five prior σ (no part is worse than that: a larger
        estimate is the linearisation running away, not the sensor)."""
        innov = super().update(z, h, r)
        self._keep_covariance()
        lim = 5.0 * self.wall.accel_bias_prior
        x = self._x
        for k in (B_X, B_Y):
            if not -lim <= x[k] <= lim:
                x[k] = min(lim, max(-lim, x[k]))
        return innov

    # -- absolute references (eqs. 10–13) -------------------------------------------
    def _update_angle(self, theta_meas: float, sigma: float) -> float:
        """θ measured; the innovation is wrapped to (−π, π]."""
        innov = _wrap(theta_meas - self._x[TH])
        h = np.zeros((1, N_STATE))
        h[0, TH] = 1.0
        self.update(np.array([self._x[TH] + innov]), h, np.array([[sigma * sigma]]))
        return innov

    def _gravity_model(self) -> tuple[float, np.ndarray]:
        """The gravity heading the state predicts, h(X) = θ + (b_x cos θ − b_y
        sin θ)/g, and its Jacobian row (eq. 11 linearised)."""
        th, bx, by = self._x[TH], self._x[B_X], self._x[B_Y]
        c, s = math.cos(th), math.sin(th)
        h = np.zeros((1, N_STATE))
        h[0, TH] = 1.0 - (bx * s + by * c) / G_MPS2
        h[0, B_X] = c / G_MPS2
        h[0, B_Y] = -s / G_MPS2
        return th + (bx * c - by * s) / G_MPS2, h

    def update_gravity_heading(self, theta_rad: float, sigma_rad: float | None = None) -> bool:
        """The accelerometer's heading on the wall plane (absolute). Returns
        False when the innovation is beyond the gate (a jolt), and counts it;
        when ``gravity_reset_after`` in a row are beyond it, the belief is
        the one at fault: its heading variance is opened to the innovation
        and the measurement taken."""
        w = self.wall
        sigma = w.gravity_heading_rad if sigma_rad is None else sigma_rad
        predicted, h = self._gravity_model()
        innov = _wrap(theta_rad - predicted)
        self.gravity_innov = innov
        s2 = float((h @ self._p @ h.T)[0, 0]) + sigma * sigma
        if innov * innov > (w.gravity_gate**2) * s2:
            self._gravity_out += 1
            self.rejected["gravity"] += 1
            if self._gravity_out < w.gravity_reset_after:
                return False
            self._p[TH, TH] = max(self._p[TH, TH], innov * innov)
            self.resets["gravity"] += 1
            predicted, h = self._gravity_model()
        self._gravity_out = 0
        # the linearised update: Z − h(X) as the innovation (eq. 11)
        self.update(np.array([float((h @ self._x)[0]) + innov]), h, np.array([[sigma * sigma]]))
        return True

    def seam_seen(self, seams, horizontal: bool, lead_m: float, circ_m: float,
                  seam_angle_rad: float | None = None, offset_m: float = 0.0) -> bool:
        """A seam in the camera's image (centre ``lead_m`` ahead of the
        axle): its direction in the image (relative to the heading, modulo π)
        fixes θ; the nearest mapped seam of that direction to where the
        belief puts the seen one (camera point + ``offset_m`` along y for a
        girth seam, x for a vertical one), if within the gate, fixes y or x.
        ``seams``: objects with x0_m, y0_m, x1_m, y1_m (the wall's map).
        Returns whether a position fix was made."""
        w = self.wall
        if seam_angle_rad is not None:
            along = 0.0 if horizontal else math.pi / 2
            theta = along - seam_angle_rad
            theta += math.pi * round((self._x[TH] - theta) / math.pi)  # nearest branch
            self._update_angle(theta, w.seam_angle_rad)
        x, y, th = self.pose
        cx, cy = x + lead_m * math.cos(th), y + lead_m * math.sin(th)
        if horizontal:
            cy += offset_m
        else:
            cx += offset_m
        k = Y if horizontal else X
        along = X if horizontal else Y  # the seam's own direction
        margin = w.seam_span_sigmas * math.sqrt(max(0.0, self._p[along, along]))
        best = nearest_seam_offset(seams, horizontal, cx, cy, circ_m, margin)
        if best is None or abs(best) > w.seam_gate_m:
            self.rejected["seam"] += 1
            return False
        # innovation gate: a seam further from the belief than its σ allows is
        # another seam than the one seen (the map repeats every plate) unless
        # the sightings keep disagreeing, when the belief is the one at fault
        if best * best > w.seam_sigmas**2 * (self._p[k, k] + w.seam_m**2):
            self._seam_out += 1
            self.rejected["seam"] += 1
            if self._seam_out < w.seam_reset_after:
                return False
            self._p[k, k] = max(self._p[k, k], best * best)
            self.resets["seam"] += 1
        self._seam_out = 0
        h = np.zeros((1, N_STATE))
        h[0, k] = 1.0
        self.update(np.array([self._x[k] + best]), h, np.array([[w.seam_m**2]]))
        return True

    def rim_model(self, centre_x: float, centre_y: float, lead_m: float, circ_m: float
                  ) -> tuple[np.ndarray, np.ndarray]:
        """The mapped centre C as the camera (``lead_m`` ahead of the axle) would
        see it on the belief, h(X) = R(θ)ᵀ (C − c) in the body frame (forward,
        left), and its Jacobian (eq. 11 linearised): with D = C − c and
        (h_f, h_l) = h,

            ∂h/∂x = (−cos θ, sin θ),  ∂h/∂y = (−sin θ, −cos θ),
            ∂h/∂θ = (h_l, −h_f − L)."""
        x, y, th = self.pose
        c, s = math.cos(th), math.sin(th)
        dx = (centre_x - x - lead_m * c + circ_m / 2) % circ_m - circ_m / 2
        dy = centre_y - y - lead_m * s
        hf, hl = c * dx + s * dy, -s * dx + c * dy
        h = np.zeros((2, N_STATE))
        h[0, X], h[0, Y], h[0, TH] = -c, -s, hl
        h[1, X], h[1, Y], h[1, TH] = s, -c, -hf - lead_m
        return np.array([hf, hl]), h

    def rim_seen(self, discs, lead_m: float, circ_m: float,
                 offset_fwd_m: float, offset_left_m: float,
                 centre_fwd_m: float, centre_left_m: float) -> bool:
        """A manhole's or nozzle's rim in the camera's image (centre ``lead_m``
        ahead of the axle): ``offset_*`` from the image centre to the rim's
        nearest point, ``centre_*`` to the rim's centre, body frame.
        ``discs``: objects with x_m, y_m, diameter_m (the wall's map). A disc
        whose radius is the one seen (within ``rim_radius_m``) and whose centre
        lies within ``rim_gate_m`` of where the belief puts the centre seen is
        taken; the centre seen, from the nearest point along the normal at the
        map's radius (σ ``rim_m`` along the normal, r·``rim_angle_rad`` across
        it), against :meth:`rim_model` (eq. 11). Returns whether a fix was made."""
        w = self.wall
        of, ol = offset_fwd_m, offset_left_m
        nf, nl = centre_fwd_m - of, centre_left_m - ol
        r_seen = math.hypot(nf, nl)
        if not r_seen > 1e-6:  # no direction to the centre (or NaN): not a rim
            self.rejected["rim"] += 1
            return False
        nf, nl = nf / r_seen, nl / r_seen
        x, y, th = self.pose
        c, s = math.cos(th), math.sin(th)
        best = None
        for d in discs:
            r = d.diameter_m / 2
            if abs(r_seen - r) > w.rim_radius_m:
                continue
            mf, ml = of + r * nf, ol + r * nl  # the centre seen, at the map's radius
            ex = x + (lead_m + mf) * c - ml * s  # where the belief puts it
            ey = y + (lead_m + mf) * s + ml * c
            dist = math.hypot((d.x_m - ex + circ_m / 2) % circ_m - circ_m / 2, d.y_m - ey)
            if dist <= w.rim_gate_m and (best is None or dist < best[0]):
                best = (dist, d, r, mf, ml)
        if best is None:
            self.rejected["rim"] += 1
            return False
        _, d, r, mf, ml = best
        predicted, h = self.rim_model(d.x_m, d.y_m, lead_m, circ_m)
        innov = np.array([mf, ml]) - predicted
        n = np.array([nf, nl])
        t = np.array([-nl, nf])
        rr = w.rim_m**2 * np.outer(n, n) + (r * w.rim_angle_rad)**2 * np.outer(t, t)
        s2 = h @ self._p @ h.T + rr
        if float(innov @ np.linalg.solve(s2, innov)) > w.seam_sigmas**2:
            # another rim, or the belief is off: refused unless it keeps disagreeing
            self._rim_out += 1
            self.rejected["rim"] += 1
            if self._rim_out < w.seam_reset_after:
                return False
            e2 = float(innov @ innov)
            self._p[X, X] = max(self._p[X, X], e2)
            self._p[Y, Y] = max(self._p[Y, Y], e2)
            self.resets["rim"] += 1
        self._rim_out = 0
        self.update(h @ self._x + innov, h, rr)
        return True
