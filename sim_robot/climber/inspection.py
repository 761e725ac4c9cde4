"""A headless inspection of a tank wall: plan the coverage (seed 001), drive
the climber's probe over every planned cell, read the thickness, and report
coverage and the thinnest spot.

The probe sits at the body's front face (seed 001 Fig. 2, n = 0), l = L/2
ahead of the wheel axle midpoint. Steering that point instead of the axle
makes the differential drive exactly invertible (feedback linearisation):

    [ẋ_P, ẏ_P] = R(θ)·[v, l·ω]  ⇒  v = u·(cos θ, sin θ),  ω = u·(−sin θ, cos θ)/l

for a wanted probe velocity u pointing at the next cell centre.

Steering pose: ``localise="truth"`` (the true pose; slip only slows the run)
or ``"ekf"``: encoders and gyro fused by the EKF of app/core/localisation
(seed 003 §2.2, eqs. 4–13), gyro bias from a standstill before the start.
With the EKF each reading is filed under the cell the robot believes its
probe is over, as a real crawler would; ``probed`` still counts the cells the
probe physically passed over. The seed-003 EKF fixes the heading, not the distance
lost to slip under gravity, so the believed position drifts with no
absolute reference. With ``gravity`` and ``seam_fixes`` the wall EKF
(app/core/localisation/wall_ekf.py) takes the accelerometer's gravity heading
and the camera's sightings of seams and of the shell's edges (direction and
offset in the image; :meth:`WallWorld.seam_sightings`) and learns the
gravity slip from them. Seed 003
gets its reference from RTAB-Map instead. The gyro's bias wanders by
``imu_walk`` rad/s per √s (2e-6: about 0.4°/h after an hour, a tactical
MEMS part; the patrol robot's default, 2e-4, would turn tens of degrees over
a day's crawl).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np

from app.core.localisation.ekf import OdometryEkf
from app.core.localisation.wall_ekf import WallEkf, nearest_seam_offset
from app.core.planner.coverage import wrap_plan
from app.core.planner.coverage.wall import shell_landmarks

from ..sensors import Imu, WheelEncoders
from .accel_stops import calibrate_accelerometer
from .accelerometer import WallAccelerometer
from .edge_seek import EdgeSeek
from .kinematics import ClimberBody, ClimberParams, ClimberState
from .seam_detour import X_FIX_LANES, SeamDetour
from .sure_ends import SureEnds, probe_sigma_y, run_ends
from .turns import lane_change_turns, sideways, step_heading, turn_to
from .wall_world import WallWorld

log = logging.getLogger(__name__)



def lane_options(localise: str, seam_fixes: bool, lanes: str,
                 turns_in_place: bool | None = None,
                 x_fix_lanes: int | None = None) -> tuple[bool, int]:
    """``(turns_in_place, x_fix_lanes)`` as :func:`inspect_wall` takes them: a
    value given is kept; one left ``None`` is on (True, :data:`X_FIX_LANES`)
    when the estimate steers with seam fixes on vertical lanes, the setting
    measured best on the tank (docs/climber.md), else off (False, 0)."""
    best = localise == "ekf" and seam_fixes and lanes == "vertical"
    if turns_in_place is None:
        turns_in_place = best
    if x_fix_lanes is None:
        x_fix_lanes = X_FIX_LANES if best else 0
    return turns_in_place, x_fix_lanes


@dataclass
class InspectionResult:
    planned: int  # reachable cells the plan visits
    probed: int  # of those, cells the probe read
    measured: np.ndarray = field(repr=False)  # mm, NaN where not read
    sim_time_s: float = 0.0
    thinnest_mm: float = math.nan
    thinnest_cell: tuple[int, int] | None = None
    filed: np.ndarray | None = field(default=None, repr=False)  # readings by believed cell
    final_error_m: float = 0.0  # believed − true probe position at the end
    seeks: tuple[int, int, int] = (0, 0, 0)  # edge seeks: started, edge found, given up
    detours: tuple[int, int] = (0, 0)  # detours to a vertical seam: driven, cells on them
    sure_seeks: int = 0  # edge seeks for a lane's end the estimate was not sure of
    sure_fixes: tuple[int, int] = (0, 0)  # routes to a height landmark for one: driven, cells
    unsure: tuple[tuple[int, int], ...] = ()  # ends the robot believes not surely probed
    visits: int = 0  # entries of the believed probe point into a free cell

    @property
    def repetition(self) -> float:
        """Visits beyond one per planned cell, as a share of them."""
        return self.visits / self.planned - 1.0 if self.planned else 0.0

    @property
    def coverage(self) -> float:
        return self.probed / self.planned if self.planned else 1.0


def _probe_point(s: ClimberState, lead_m: float) -> tuple[float, float]:
    return s.x_m + lead_m * math.cos(s.theta_rad), s.y_m + lead_m * math.sin(s.theta_rad)


def seam_fix(
    ekf: OdometryEkf,
    seams,
    horizontal: bool,
    lead_m: float,
    circ_m: float,
    seam_angle_rad: float | None = None,
    gate_m: float = 1.0,
    sigma_m: float = 0.01,
    sigma_angle_rad: float = math.radians(1.0),
) -> bool:
    """Correct the EKF by a seam seen under the camera: the nearest mapped seam
    of that direction to the believed camera point, if within ``gate_m``.
    ``seam_angle_rad`` is the seam's direction in the image (relative to the
    body's heading, modulo π): it fixes the heading too. Returns whether a
    position update was made."""
    x, y, th = ekf.pose
    if seam_angle_rad is not None:
        along = 0.0 if horizontal else math.pi / 2
        theta = along - seam_angle_rad
        theta += math.pi * round((th - theta) / math.pi)  # the branch nearest the belief
        h = np.zeros((1, 6))
        h[0, 2] = 1.0
        ekf.update(np.array([ekf.state[2] + (theta - th)]), h, np.array([[sigma_angle_rad**2]]))
        x, y, th = ekf.pose
    cx, cy = x + lead_m * math.cos(th), y + lead_m * math.sin(th)
    best = nearest_seam_offset(seams, horizontal, cx, cy, circ_m)
    if best is None or abs(best) > gate_m:
        return False
    h = np.zeros((1, 6))
    k = 1 if horizontal else 0
    h[0, k] = 1.0
    ekf.update(np.array([ekf.state[k] + best]), h, np.array([[sigma_m**2]]))
    return True


def inspect_wall(
    world: WallWorld,
    start: tuple[int, int],
    params: ClimberParams | None = None,
    dt_s: float = 0.05,
    gain: float = 2.0,
    reach_m: float = 0.02,
    seed: int = 0,
    max_steps_per_cell: int = 400,
    localise: str = "truth",
    seam_fixes: bool = False,
    imu_walk: float = 2e-6,
    gravity: bool = False,
    lanes: str = "planner",
    seek: bool = False,
    accel_calibration: bool = False,
    turns_in_place: bool | None = None,
    x_fix_lanes: int | None = None,
    sure_ends: bool | None = None,
) -> InspectionResult:
    """Cover the wall from ``start`` (row, col of the probe) and probe it.

    With ``gravity`` or ``seam_fixes`` the estimator is the wall EKF
    (app/core/localisation/wall_ekf.py: gravity slip in the motion model,
    learnt from the landmarks); ``gravity`` adds the accelerometer's
    absolute heading. ``lanes="vertical"`` sweeps the whole wall up and
    down, so that every lane crosses the girth seams and reaches the shell's
    edges (a height fix per course); "planner" sweeps the sub-regions of
    §3.2, each along its fewer-turn axis (§3.4), or the whole wall in lanes
    along rows or columns, whichever turns least round the seam
    (:func:`~app.core.planner.coverage.seam.wrap_plan`). With the estimate
    steering and the camera's landmarks on, ``seek`` climbs (or descends) to
    the shell's edge when an edge row's cell is reached and the camera has
    not seen the edge (:mod:`.edge_seek`; off by default: measured mixed on
    the tank, docs/climber.md). With ``gravity``, ``accel_calibration`` first
    stands still at four headings a quarter turn apart and gives the filter
    the accelerometer's bias from them (:func:`.accel_stops.calibrate_accelerometer`;
    off by default: with the bias known, lanes drifted more, docs/climber.md).
    ``turns_in_place`` makes each sideways step between lanes in place: turn to
    face along the wall's horizontal, step, turn to face the new lane
    (:mod:`.turns`). ``x_fix_lanes`` > 0 (with the estimate steering and seam
    fixes): after that many lane changes without a fix of the belief's x,
    drive to the nearest vertical seam of the row at the next lane's end and
    back (:mod:`.seam_detour`). Left ``None``, both are on (turns in place,
    a detour every :data:`X_FIX_LANES` lanes) with ``localise="ekf"``,
    ``seam_fixes`` and ``lanes="vertical"``, and off otherwise
    (:func:`lane_options`); ``turns_in_place=False, x_fix_lanes=0`` is the
    behaviour from before they were on by default. ``sure_ends`` (with the
    estimate steering and seam fixes; left ``None``, on where the detours are,
    so off with ``x_fix_lanes=0``):
    at each end of the route's vertical runs the estimate's height and its
    covariance judge whether the probe is surely in the cell's row; when not, the
    crawler seeks the shell's edge if it is near, else drives across the nearest
    girth seam, and comes back to the cell (:mod:`.sure_ends`); the ends never
    judged sure are reported."""
    if localise not in ("truth", "ekf"):
        raise ValueError(f"localise must be 'truth' or 'ekf', got {localise!r}")
    if lanes not in ("planner", "vertical"):
        raise ValueError(f"lanes must be 'planner' or 'vertical', got {lanes!r}")
    turns_in_place, x_fix_lanes = lane_options(localise, seam_fixes, lanes,
                                               turns_in_place, x_fix_lanes)
    if sure_ends is None:  # on where the detours are (not in the behaviour from before)
        sure_ends = x_fix_lanes > 0
    params = params or ClimberParams()
    lead = params.length_m / 2
    if lanes == "vertical":
        plan = wrap_plan(world.blocked, start, regions=False, axis=1)
    else:
        plan = wrap_plan(world.blocked, start, regions=True)
    x0, y0 = world.cell_centre(*start)
    body = ClimberBody(
        params,
        ClimberState(x0 - lead, y0, 0.0),
        world.circ_m,
        seed=seed,
        height_m=world.spec.height_m,
    )
    rng = np.random.default_rng(500 + seed)
    enc = WheelEncoders(rng, params.wheel_radius_m, params.ticks_per_rev, slip=0.0)
    imu = Imu(rng, walk_rps_per_sqrt_s=imu_walk)
    bias = float(np.mean([imu.sample(dt_s, 0.0) for _ in range(int(10.0 / dt_s))]))
    wall_ekf = gravity or seam_fixes
    ekf = (WallEkf if wall_ekf else OdometryEkf)(x0 - lead, y0, 0.0, track_m=params.track_m)
    accel = WallAccelerometer(rng)
    landmarks = shell_landmarks(world.spec)
    rims = (*world.spec.manholes, *world.spec.nozzles)
    ticks = enc.step(0.0, 0.0, 0.0)
    measured = np.full(world.blocked.shape, np.nan)
    filed = np.full(world.blocked.shape, np.nan)
    sim_t = 0.0

    def pose() -> tuple[float, float, float]:
        if localise == "ekf":
            return ekf.pose
        return body.s.x_m, body.s.y_m, body.s.theta_rad

    seeker = (EdgeSeek(world.rows, world.spec.height_m)
              if seek and localise == "ekf" and seam_fixes else None)
    detour = (SeamDetour(world.blocked, world.spec.seams, world.cell_m, x_fix_lanes)
              if x_fix_lanes > 0 and localise == "ekf" and seam_fixes else None)
    ends = (SureEnds(world.rows, world.cell_m, blocked=world.blocked, seams=world.spec.seams)
            if sure_ends and localise == "ekf" and seam_fixes else None)
    # the edge seek of an unsure end: the option's own seeker when on, else one that
    # never starts by itself
    end_seeker = seeker or (EdgeSeek(world.rows, world.spec.height_m) if ends else None)

    def drive(ux: float, uy: float) -> None:
        """One control step with the probe's wanted velocity (ux, uy)."""
        x, y, th = pose()
        c, s = math.cos(th), math.sin(th)
        move(ux * c + uy * s, (-ux * s + uy * c) / lead)

    last_f = [0.0, 0.0]  # the accelerometer's last specific force (f_x, f_y)
    visit = [None, 0]  # the believed probe's cell, entries into free cells

    def move(v: float, w: float) -> None:
        """One control step at body speed v and yaw rate w: the body moves,
        the sensors and the camera feed the estimator, the probe reads the
        cell under it."""
        nonlocal ticks, sim_t
        vl, vr, w_true = body.step(v, w, dt_s)
        sim_t += dt_s
        if localise == "ekf":
            t2 = enc.step(dt_s, vl, vr)
            dl = (t2[0] - ticks[0]) / enc.ticks_per_m
            dr = (t2[1] - ticks[1]) / enc.ticks_per_m
            gyro = imu.sample(dt_s, w_true) - bias
            if wall_ekf:  # the interval's own rates carry the pose (no lag for the gravity)
                ekf.advance(dt_s, dl, dr, gyro)
            else:  # seed 003's order, as the odometry-only figures were measured
                ekf.predict(dt_s)
                ekf.update_encoders(dl, dr, dt_s)
                ekf.update_imu_yaw_rate(gyro)
            ticks = t2
            if gravity:
                fx, fy = accel.sample(dt_s, body.s.theta_rad, body.v_true_mps, w_true)
                last_f[:] = (fx, fy)
                ekf.update_gravity_heading(accel.heading(dt_s, fx, fy, (vl + vr) / 2, gyro))
            if seam_fixes:
                cx, cy = _probe_point(body.s, lead)  # the camera looks where the probe is
                for flat, seen, off in world.seam_sightings(cx, cy, body.s.theta_rad, rng):
                    fix = ekf.seam_seen(landmarks, flat, lead, world.circ_m, seen, off)
                    if fix and flat and end_seeker is not None:
                        bx, by, bth = ekf.pose
                        end_seeker.fixed(by + lead * math.sin(bth) + off)
                    if fix and not flat and detour is not None:
                        detour.fixed()
                for seen in world.rim_sightings(cx, cy, body.s.theta_rad, rng):
                    if ekf.rim_seen(rims, lead, world.circ_m, *seen) and detour is not None:
                        detour.fixed()
            if end_seeker is not None:
                end_seeker.moved(*believed_probe())
        here = world.cell_of(*believed_probe())
        if here != visit[0]:
            visit[0] = here
            visit[1] += here is not None and not world.blocked[here]
        px, py = _probe_point(body.s, lead)
        cell = world.cell_of(px, py)
        if cell is not None and math.isnan(measured[cell]):
            reading = world.probe(px, py)
            if reading is not None:
                measured[cell] = reading
                believed = world.cell_of(*believed_probe())
                # a reading believed to lie on an obstacle is dropped: the
                # map says no probe can couple there
                if (
                    believed is not None
                    and not world.blocked[believed]
                    and math.isnan(filed[believed])
                ):
                    filed[believed] = reading

    def heading() -> float:
        return pose()[2]

    def believed_probe() -> tuple[float, float]:
        x, y, th = pose()
        return x + lead * math.cos(th), y + lead * math.sin(th)

    def approach(tx: float, ty: float) -> bool:
        """Steer the probe onto (tx, ty) as the belief puts it; whether reached."""
        for _ in range(max_steps_per_cell):
            px, py = believed_probe()
            ex, ey = world.wrap_dx(tx - px), ty - py
            if math.hypot(ex, ey) < reach_m:
                return True
            ux, uy = gain * ex, gain * ey
            speed = math.hypot(ux, uy)
            if speed > params.v_max_mps:
                ux, uy = ux * params.v_max_mps / speed, uy * params.v_max_mps / speed
            drive(ux, uy)
        return False

    if wall_ekf and gravity and accel_calibration:
        cal = calibrate_accelerometer(move, lambda: last_f, ekf, dt_s)
        if cal is not None:
            ekf.set_accel_bias(cal.bias, cal.sigma)

    def drive_cells(route: list[tuple[int, int]], here: tuple[int, int]) -> None:
        """Drive through adjacent cells from ``here``; with turns in place, turn
        to face along each straight leg first."""
        facing = None
        for cell in route:
            if turns_in_place:
                way = step_heading(here, cell, world.cols)
                if way != facing:
                    turn_to(move, heading, dt_s, way)
                    facing = way
            approach(*world.cell_centre(*cell))
            here = cell

    def seek_edge(sk: EdgeSeek) -> None:
        """Drive the probe as the seek ``sk`` asks until it ends."""
        for _ in range(max_steps_per_cell):
            u = sk.velocity(believed_probe()[1])
            if u is None:
                break
            drive(*u)
        else:
            sk.abandon()

    def sure_end(cell: tuple[int, int], nxt: tuple[int, int] | None) -> bool:
        """At an end of a vertical run, reached as the belief puts it: whether the
        probe is surely in the cell's row; when not, seek the shell's edge if it is
        near, else cross the nearest girth seam, and come back (:mod:`.sure_ends`);
        then face the step to ``nxt``. Whether reached."""
        assert ends is not None and end_seeker is not None
        cov, th = ekf.covariance, ekf.pose[2]
        sure, side, there, back = ends.check(cell, believed_probe()[1],
                                             probe_sigma_y(cov, th, lead))
        reached = True
        if side:
            end_seeker.begin(side, believed_probe()[1])
            seek_edge(end_seeker)
            reached = approach(*world.cell_centre(*cell))
        elif there:
            drive_cells(there, cell)  # across a girth seam, or to an edge row
            if end_seeker.arrived(there[-1][0], believed_probe()[1]):
                seek_edge(end_seeker)  # the edge not seen on the way: seek it
            drive_cells(back, there[-1])
            reached = approach(*world.cell_centre(*cell))
        if side or there:
            cov, th = ekf.covariance, ekf.pose[2]
            sure = ends.sure(cell[0], believed_probe()[1], probe_sigma_y(cov, th, lead))
            log.debug("unsure end %s: after the %s, dy %.3f m, sigma_y %.3f m, sure %s",
                      cell, "edge seek" if side else f"route of {len(there)} cells",
                      believed_probe()[1] - world.cell_centre(*cell)[1],
                      probe_sigma_y(cov, th, lead), sure)
        ends.judged(cell, sure)
        if there and turns_in_place and nxt is not None:
            turn_to(move, heading, dt_s, step_heading(cell, nxt, world.cols))
        return reached

    cells = plan.cells
    end_at = run_ends(cells) if ends is not None else set()
    for i, target in enumerate(cells):
        tx, ty = world.cell_centre(*target)
        prev = cells[i - 1] if i else None
        side = sideways(prev, target, world.cols)
        if detour is not None and side:
            detour.lane_changed()
            route = detour.route(prev)
            if route:  # at a lane's end: to the nearest vertical seam and back
                drive_cells(route, prev)
        # a lane change: face the step along the wall's horizontal, where no along-track
        # slip acts, and after it the new lane's way
        before, after = (lane_change_turns(prev, target, cells[i + 1] if i + 1 < len(cells)
                                           else None, world.cols)
                         if turns_in_place else (None, None))
        if before is not None:
            turn_to(move, heading, dt_s, before)
        reached = approach(tx, ty)
        if reached and seeker is not None and seeker.arrived(target[0], believed_probe()[1]):
            # the camera should see the edge here and does not: climb (or descend) to it
            seek_edge(seeker)
            reached = approach(tx, ty)  # the cell again, on the corrected belief
        if reached and i in end_at:
            reached = sure_end(target, cells[i + 1] if i + 1 < len(cells) else None)
        if after is not None:
            turn_to(move, heading, dt_s, after)
        if not reached:
            log.warning("probe did not reach cell %s", target)
    planned = len(set(plan.cells))
    probed = int(sum(1 for p in set(plan.cells) if not math.isnan(measured[p])))
    res = InspectionResult(planned, probed, measured, sim_t, filed=filed, visits=visit[1])
    if seeker is not None:
        res.seeks = (seeker.seeks, seeker.found, seeker.given_up)
    if detour is not None:
        res.detours = (detour.driven, detour.cells)
    if ends is not None:
        res.sure_seeks, res.unsure = ends.seeks, tuple(sorted(ends.unsure))
        res.sure_fixes = (ends.fixes, ends.fix_cells)
    if localise == "truth":
        res.filed = measured
    if np.isfinite(res.filed).any():
        i = np.unravel_index(int(np.nanargmin(res.filed)), res.filed.shape)
        res.thinnest_mm = float(res.filed[i])
        res.thinnest_cell = (int(i[0]), int(i[1]))
    x, y, th = pose()
    tx, ty = _probe_point(body.s, lead)
    res.final_error_m = math.hypot(
        world.wrap_dx(x + lead * math.cos(th) - tx), y + lead * math.sin(th) - ty
    )
    return res
