"""The wall climber's relay: the patrol robot's relay (same serial bridge,
command checks, control lease, deadman and failsafes, periodic publishers,
TCP server) with the climber's own parts in place of the patrol robot's map,
lidar, camera stream and patrol executor:

- the pose is the EKF's (encoders + gyro, seam fixes from the camera), sent
  as ``WALL_POSE`` on the unrolled wall, never ground truth;
- the inspection mission (:class:`~.executor.InspectionExecutor`), driven by
  the commands ``start_inspection`` / ``pause_inspection`` /
  ``resume_inspection`` / ``abort_inspection``;
- the wall and its plan (``WALL_INFO``) on connect, the coverage
  (``COVERAGE``) at 2 Hz and the probe's readings (``PROBE``) in batches at
  5 Hz (docs/protocol.md, "Wall climber");
- a contact the board reports (its ``OBSTACLE_NEAR`` flag raised: the body
  stopped at the wall's edge or an obstacle) is counted and sent as the
  patrol robot's ``collision`` event, naming what the map has there by the
  estimate; the executor gives up the move or the target at hand.

The patrol robot's :class:`~sim_robot.relay.Relay` is reused by subclassing;
its constructor builds a station's navigation, so this one sets up the
climber's own parts and takes the state both share (key, server, lease, MCU
codec, commanded speeds, counters) from ``Relay._init_link``.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable

import numpy as np

from app.comm.protocol import AlarmFlag, Command, Event, Heartbeat
from app.comm.wall_protocol import CoverageState, ProbeReadings, WallInfo, WallPose
from app.core.localisation.contact_fix import ContactFixes
from app.core.localisation.rim_camera import find_rims
from app.core.localisation.seam_camera import LineSeen, find_lines, lines_to_sightings
from app.core.planner.coverage.wall import shell_landmarks

from ..config import SimConfig
from ..mcu_link import McuType
from ..relay import Relay
from ..server import Client
from .contact import WallContact
from .executor import InspectionExecutor
from .kinematics import ClimberParams
from .odometry import ClimberOdometry, Sightings
from .reach import Reach
from .seam_detour import X_FIX_LANES, SeamDetour
from .sure_lanes import probe_sigma_x

log = logging.getLogger(__name__)

INSPECTION_COMMANDS = ("start_inspection", "pause_inspection", "resume_inspection",
                       "abort_inspection")
COVERAGE_S = 0.5  # CoverageProgress at 2 Hz (and on every state change), wall time
PROBE_S = 0.2  # probe readings in batches at 5 Hz
# the steering's shortest wall period: 0.05 s of sim time up to 25x, coarser beyond
# (at 40x a step is 0.08 s of sim time; coverage suffers above ~25x: docs/climber.md)
NAV_MIN_WALL_S = 0.002
CONTACT_NAME_MARGIN_M = 0.1  # a contact is named by what the map has this near the estimate
CAMERA_PERIOD_S = 0.1  # the seam camera's frames: 10 a second of sim time,
CAMERA_MAX_HZ = 100.0  # and at most 100 a second of wall time (a high time scale)
MOVING_MPS = 0.005  # a speed commanded above this says which side of the body led to a contact
CONTACT_AGAIN_S = 1.0  # a contact that lasts is told to the executor again this often (MCU time)


class _Nav:
    """What the shared relay parts ask of navigation: the mission executor."""

    def __init__(self, executor: InspectionExecutor) -> None:
        self.executor = executor


class ClimberRelay(Relay):
    """``wall``: the climber's map (a :class:`~.wall_world.WallMap`; of a simulated
    :class:`~.wall_world.WallWorld` the relay reads only the map: obstacles, seams,
    cells — never the thickness). ``seams_seen`` (None: no camera, as with a real
    board; then no landmark fixes and no detours to a vertical seam) gives the
    camera's view and when it was taken (sim s, the MCU's clock):
    ``(t_s, [(horizontal, angle_in_image_rad, offset_m), ...])`` — a frame's
    own time, not the time the relay gets to it (a starved robot reads frames
    late). ``rims_seen``, if given, is the same camera's view of manhole and
    nozzle rims: ``(t_s, [(near_fwd_m, near_left_m, centre_fwd_m, centre_left_m), ...])``
    (the offsets to each rim's nearest point and to its centre).
    ``seam_frames``, in place of ``seams_seen``, gives the camera's frames
    ``(t_s, frame)``, or None when it has no new one (``camera_m_per_px`` metres
    a pixel, rows against the body's forward axis, columns against its left);
    the relay finds the seams, the shell's edges and the rims in them itself
    (app/core/localisation/seam_camera.py, rim_camera.py)."""

    def __init__(self, cfg: SimConfig, open_port: Callable[[], object], wall,
                 start_pose: tuple[float, float, float], start_cell: tuple[int, int],
                 seams_seen: Callable[[], tuple[float, list[tuple[bool, float, float]]]] | None,
                 sim_time: Callable[[], float] = lambda: 0.0,
                 params: ClimberParams | None = None, limit_mm: float = 8.0,
                 wall_name: str = "tank",
                 rims_seen: Callable[[], tuple[float, list[tuple[float, ...]]]] | None = None,
                 seam_frames: Callable[[], tuple[float, np.ndarray] | None] | None = None,
                 camera_m_per_px: float = 0.001) -> None:
        self.world = None
        self.camera = None
        self.params = params or ClimberParams()
        self.spec = wall.spec
        self.landmarks = shell_landmarks(wall.spec)  # seams and the shell's edges
        self.blocked = wall.blocked
        self.cell_m = wall.cell_m
        self.circ_m = wall.circ_m
        self.nominal_mm = wall.nominal_mm
        self.limit_mm = limit_mm
        self.wall_name = wall_name
        self.start_cell = start_cell
        self.seams_seen = seams_seen
        self.rims_seen = rims_seen
        self.rims = (*wall.spec.manholes, *wall.spec.nozzles)  # their rims: landmarks too
        # the camera's grey frames, ``(t_s, frame)``, in place of ``seams_seen``: the seams
        # and the shell's edges are then found in the pixels (app/core/localisation/
        # seam_camera.py), one frame per CAMERA_PERIOD_S of sim time
        self.seam_frames = seam_frames
        self.camera_m_per_px = camera_m_per_px  # the camera's calibration
        self._radii = sorted({d.diameter_m / 2 for d in self.rims})
        self._frame_due = -math.inf
        # the edge seek (sim_robot/climber/edge_seek.py) in the executor: off, as measured
        self.seek_edges = False
        # a detour to a vertical seam after this many lanes without an x fix (0: none), as
        # inspect_wall's (sim_robot/climber/seam_detour.py)
        self.x_fix_lanes = (X_FIX_LANES if seams_seen is not None or seam_frames is not None
                            else 0)
        # the runs' ends judged by the estimate's height and its covariance, an unsure one
        # made sure by an edge seek or a route to a height landmark and back, as inspect_wall's
        # (sim_robot/climber/link_ends.py); None: on where the detours are, as there
        self.sure_ends: bool | None = None
        # the estimate's first x fix takes back every cell filed before it, for the mop-up
        # (a lean of the first lanes that fix does not show, sim_robot/climber/sure_lanes.py;
        # off: it costs the mop-up of the first lanes on every run, docs/climber.md)
        self.first_fix_whole = False
        # turns in place at the lanes' ends and along the detours, as inspect_wall's default
        # on the estimate (sim_robot/climber/turns.py)
        self.turns_in_place = True
        # the body's footprint on the map (contact.py), for the executor's moves to keep it
        # on the wall and off the obstacles (reach.py, moves.py), and to name a contact
        self.wall_contact = WallContact(wall.spec, wall.blocked, self.params.length_m,
                                        self.params.width_m)
        self.body_aware = True
        # a contact the board reports taken as a position fix on the map (contact_fix.py):
        # where the stair band hides the vertical seams, x has no other fix
        self.contact_fixes = True
        self._contact_fixer = ContactFixes()  # one fix per place
        self._contact_told = 0.0  # MCU time the executor was last told of a contact
        self._refused = 0  # the gravity headings the estimate refused, as last seen
        self._resets = 0  # ... and the runs of them the filter ended by its reset
        self._belief_xy = start_pose[:2]  # the belief's axle at the last report
        self.odom = ClimberOdometry(self.params, *start_pose)
        self.sightings = Sightings()  # the camera's, waiting for the estimate to reach them
        self._init_link(cfg, open_port, sim_time, min(cfg.speed_limit_mps, self.params.v_max_mps),
                        counters=("probe", "coverage", "seam_fixes", "rim_fixes", "contacts",
                                  "contact_fixes", "frames"))
        self.localise = True
        self.nav_ready = threading.Event()
        self.inspection: InspectionExecutor | None = None
        self.nav = None
        self.wall_msg: WallInfo | None = None
        self._introduced: set[int] = set()  # desks sent the wall's description

    # ------------------------------------------------------------------ lifecycle
    def prepare(self) -> None:
        """Plan the coverage (a first run compiles the planner's kernels)."""
        if self.nav_ready.is_set():
            return
        t0 = time.monotonic()
        reach = (Reach(self.wall_contact, self.params.length_m / 2) if self.body_aware
                 else None)
        route_blocked = self.blocked if reach is None else reach.body_blocked()
        detour = (SeamDetour(route_blocked, self.spec.seams, self.cell_m, self.x_fix_lanes)
                  if self.x_fix_lanes > 0 else None)
        sure = self.x_fix_lanes > 0 if self.sure_ends is None else self.sure_ends
        ex = InspectionExecutor(self.blocked, self.cell_m, self.start_cell, self.params,
                                seek_edges=self.seek_edges, detour=detour,
                                turns_in_place=self.turns_in_place, reach=reach,
                                sure_ends=sure, seams=self.spec.seams,
                                first_fix_whole=self.first_fix_whole)
        ex.plan_apart = True  # the mop-up's route planned off the lock, the robot still
        self.inspection = ex
        self.nav = _Nav(ex)
        seams = [[b.x0_m, b.y0_m, b.x1_m, b.y1_m] for b in self.spec.seams]
        self.wall_msg = WallInfo.build(self.wall_name, self.cell_m, self.blocked, ex.labels,
                                       ex.order, ex.cells, self.nominal_mm, self.limit_mm,
                                       seams)
        log.info("coverage plan: %d cells, %d reachable, %.1f s", len(ex.cells), ex.reachable,
                 time.monotonic() - t0)
        self.nav_ready.set()

    # ------------------------------------------------------------------ desks
    def _on_connect(self, c: Client) -> None:
        self.event("info", "client_connected", f"desk {c.name} connected", client=c.name,
                   clients=len(self.server.clients))
        c.send(Heartbeat(Heartbeat.ROLE_ROBOT, 0, 0, 0))
        c.send(Event("info", "lease", self._lease_text(), self.lease_info()))
        c.send(self.wall_msg)
        with self._lock:
            c.send(self.inspection.progress())
            self._introduced.add(c.id)

    def _on_disconnect(self, c: Client) -> None:
        with self._lock:
            self._introduced.discard(c.id)
        super()._on_disconnect(c)

    def _wall_broadcast(self, msg) -> None:
        """To the desks that have the wall's description: the server lists a
        desk before _on_connect has sent it, and a desk cannot place coverage,
        readings or a pose on a wall it has not been told of."""
        with self._lock:
            ids = set(self._introduced)
        for c in self.server.clients:
            if c.id in ids:
                c.send(msg)

    def _tick_pose(self) -> None:
        with self._lock:
            o = self.odom
            p = WallPose(o.x % self.circ_m, o.y, o.theta, o.v, o.omega, o.sigma_m)
        self._wall_broadcast(p)
        self.counters["pose"] += 1

    def _tick_scan(self) -> None:
        """The climber has no lidar."""

    # ------------------------------------------------------------------ MCU
    def _on_report(self, rep) -> None:
        was = self.last_flags & AlarmFlag.OBSTACLE_NEAR
        super()._on_report(rep)
        self._judge_refusals()
        if self.inspection is not None and len(self.sightings):
            with self._lock:  # the sightings this report's estimate has reached
                self._use_sightings()
        if not rep.alarm_flags & AlarmFlag.OBSTACLE_NEAR:
            return
        t_s = rep.mcu_time_ms / 1000.0
        if not was:
            self._on_contact(t_s)
        elif t_s - self._contact_told >= CONTACT_AGAIN_S:  # still pressed against it
            with self._lock:
                self._contact_told = t_s
                if self.inspection is not None:
                    self.inspection.touched(self.sim_time(), self.cmd_v)

    def _judge_refusals(self) -> None:
        """The gravity headings the estimate refused make the lanes unsure
        (sure_lanes.py): each refusal with its innovation, the belief's axle's move
        since the last report, and the end of a run of refusals, by the filter's
        reset or by a heading taken."""
        ekf = self.odom.ekf
        refused, resets = ekf.rejected["gravity"], ekf.resets["gravity"]
        x, y, _ = ekf.pose
        moved = math.hypot(x - self._belief_xy[0], y - self._belief_xy[1])
        self._belief_xy = (x, y)
        if self.inspection is not None:
            with self._lock:
                lanes = self.inspection.lanes
                lanes.moved(moved)
                for _ in range(refused - self._refused):
                    lanes.refused(ekf.gravity_innov)
                if resets != self._resets or ekf.gravity_out == 0:
                    lanes.resolved(resets != self._resets)
        self._refused, self._resets = refused, resets

    def _on_contact(self, t_s: float) -> None:
        """The board's contact flag rose: count it, tell the executor, and send the
        patrol robot's ``collision`` event, naming what the map has within
        CONTACT_NAME_MARGIN_M of the body as the estimate puts it (never the truth)."""
        with self._lock:
            x, y, th = self.odom.ekf.pose
            self.counters["contacts"] += 1
            self._contact_told = t_s
            if self.contact_fixes:
                self._contact_fix()
            if self.inspection is not None:
                self.inspection.touched(self.sim_time(), self.cmd_v)
        x %= self.circ_m
        what = self.wall_contact.touches(x, y, th, CONTACT_NAME_MARGIN_M) or "unknown"
        self.event("alarm", "collision", f"the climber touched the {what} near "
                   f"({x:.2f}, {y:.2f}) (its estimate)", what=what, x_m=round(x, 2),
                   y_m=round(y, 2), t_s=round(t_s, 2))

    def _contact_fix(self) -> None:
        """The body stopped against the map: the estimate is moved onto the poses where
        its footprint touches the map (app/core/localisation/contact_fix.py; under the
        lock). It leaves x to a few cm (a tread of the stair's staircase of cells), not
        the 1 cm of a seam, so the executor is not told of it as of an x fix (which would
        put off the next detour to a seam and judge the lanes since by it). A contact at
        the last fix's place is not folded in again (``ContactFixes``). The speed last
        commanded says which side of the body met the map (a turn in place: either)."""
        fix = self._contact_fixer.on_contact(
            self.odom.ekf, lambda x, y, th, grow: self.wall_contact.depth(x, y, th, grow)[0],
            moving=self._moving())
        if fix.fixed:
            self.counters["contact_fixes"] += 1

    def _moving(self) -> float:
        """The speed last commanded, when it says which side of the body led: a drive
        along the heading, not a turn (in place, or one whose corners' swing is a fair
        share of the speed: then a trailing corner can be the one that touched); else 0."""
        v, w = self.cmd_v, self.cmd_w
        if abs(v) <= MOVING_MPS or abs(w) * self.wall_contact.reach_m > 0.5 * abs(v):
            return 0.0
        return v

    def _on_mcu_frame(self, fr) -> None:
        if fr.msg_type != McuType.PROBE_REPORT or self.inspection is None:
            return
        with self._lock:
            self.inspection.reading(self.odom.ekf.pose, fr.message.thickness_mm)

    # ------------------------------------------------------------------ commands
    def handle_command(self, cmd: Command, client: Client | None = None) -> tuple[bool, str]:
        if cmd.name in ("look_at",):
            return False, "the wall climber has no pan-tilt camera"
        if cmd.name not in INSPECTION_COMMANDS:
            return super().handle_command(cmd, client)
        with self._lock:
            ex = self.inspection
            t = self.sim_time()
            if cmd.name in ("start_inspection", "resume_inspection") and self.estop:
                return False, "estop latched; send reset_estop first"
            if cmd.name == "start_inspection":
                ok, why = ex.start(t)
            elif cmd.name == "pause_inspection":
                ok, why = ex.pause("operator")
                self._set_cmd(0.0, 0.0)
            elif cmd.name == "resume_inspection":
                ok, why = ex.resume(t)
            else:
                ok, why = ex.abort("operator")
                self._set_cmd(0.0, 0.0)
        if ok:
            self.event("info", "inspection", f"inspection {CoverageState.NAMES[ex.state]}",
                       state=CoverageState.NAMES[ex.state])
        return ok, why

    # ------------------------------------------------------------------ navigation
    def _nav_loop(self) -> None:
        """Seam fixes, steering and the coverage/probe streams, one step per
        control period (0.05 s sim), paced in wall time like the patrol robot's."""
        ex = self.inspection
        period = min(0.1, max(NAV_MIN_WALL_S, 0.05 / self.cfg.time_scale))
        nxt = time.monotonic()
        due = {"coverage": nxt, "probe": nxt}
        version = ex.version
        while not self._stop.wait(max(0.0, nxt - time.monotonic())):
            now = time.monotonic()
            nxt = max(nxt + period, now)
            t = self.sim_time()
            seen = self._look(t)  # (the image work outside the lock)
            with self._lock:
                if self.seams_seen is not None:
                    self.sightings.add("seam", *self.seams_seen())
                if seen is not None:
                    t_frame, lines, rims = seen
                    self.sightings.add("lines", t_frame, lines)
                    self.sightings.add("rim", t_frame, rims)
                    self.counters["frames"] += 1
                if self.rims_seen is not None:
                    self.sightings.add("rim", *self.rims_seen())
                self._use_sightings()
                was_running = ex.owns_motors
                v, w = ex.step(self.odom.ekf.pose, t, self.odom.t_s, self.odom.ekf.covariance)
                if self.on_control_step is not None:
                    # the simulation paces its clock by the estimate the step steered on:
                    # reports the relay has not yet read (a backlog after a long contact
                    # fix, a starved process) are motion it steered blind through
                    self.on_control_step(t if self.odom.t_s is None else min(t, self.odom.t_s))
                if (ex.owns_motors or was_running) and not self.estop:
                    self._set_cmd(v, w)
                self.counters["nav_steps"] += 1
                changed = ex.version != version
                version = ex.version
                readings = ex.take_readings() if now >= due["probe"] else None
                progress = ex.progress() if changed or now >= due["coverage"] else None
            if changed and ex.state == CoverageState.DONE:
                self.event("info", "inspection", "inspection done", state="done")
            if readings is not None:
                due["probe"] = now + PROBE_S
                if len(readings):
                    self._wall_broadcast(ProbeReadings(readings))
                    self.counters["probe"] += len(readings)
            if progress is not None:
                due["coverage"] = now + COVERAGE_S
                self._wall_broadcast(progress)
                self.counters["coverage"] += 1

    def _look(self, t: float) -> tuple[float, list[tuple], list[tuple]] | None:
        """A camera frame's lines and rims when one is due (:data:`CAMERA_PERIOD_S`
        of sim time apart, and at most CAMERA_MAX_HZ frames per second of wall time
        at a high time scale): ``(t_frame, [(angle, fwd, left, kind), ...],
        [(near_fwd, near_left, centre_fwd, centre_left), ...])``
        (app/core/localisation/seam_camera.py, rim_camera.py)."""
        if self.seam_frames is None or t < self._frame_due:
            return None
        self._frame_due = t + max(CAMERA_PERIOD_S, self.cfg.time_scale / CAMERA_MAX_HZ)
        got = self.seam_frames()
        if got is None:  # (a real camera: no new frame yet)
            return None
        t_frame, frame = got
        m = self.camera_m_per_px
        lines = find_lines(frame, m)
        rims = find_rims(frame, m, self._radii) if self._radii else []
        return t_frame, [(ln.angle_rad, ln.fwd_m, ln.left_m, ln.kind) for ln in lines], rims

    def _use_sightings(self) -> None:
        """Fold in the camera's sightings the estimate has reached (odometry.Sightings;
        under the lock)."""
        ex, lead = self.inspection, self.params.length_m / 2
        for t_frame, kind, what in self.sightings.due(self.odom.t_s):
            if kind == "lines":  # on the heading the estimate has at the frame's time
                for seen in lines_to_sightings([LineSeen(*what)], self.odom.ekf.pose[2]):
                    self._seam_fix(seen, t_frame)
            elif kind == "seam":
                self._seam_fix(what, t_frame)
            else:
                before = self.odom.ekf.pose
                if self.odom.rim_seen(self.rims, *what, lead, self.circ_m, t_frame):
                    self.counters["rim_fixes"] += 1
                    ex.x_fixed(*self._x_moved(before))

    def _seam_fix(self, seen: tuple[bool, float, float], t_frame: float) -> None:
        ex, lead = self.inspection, self.params.length_m / 2
        horizontal, angle, offset = seen
        before = self.odom.ekf.pose
        if self.odom.seam_seen(self.landmarks, horizontal, angle, lead,
                               self.circ_m, offset, t_frame):
            self.counters["seam_fixes"] += 1
            if horizontal:  # where the corrected belief puts the line seen
                _, y, th = self.odom.ekf.pose
                ex.edge_fixed(y + lead * math.sin(th) + offset)
            else:
                ex.x_fixed(*self._x_moved(before))

    def _x_moved(self, before: tuple[float, float, float]) -> tuple[float, float]:
        """How far a fix moved the probe's believed x from ``before`` (the pose before
        it; the short way round), and the probe's x deviation after it."""
        ex = self.inspection
        after = self.odom.ekf.pose
        dx = ex.probe_point(after)[0] - ex.probe_point(before)[0]
        dx = (dx + self.circ_m / 2) % self.circ_m - self.circ_m / 2
        return dx, probe_sigma_x(self.odom.ekf.covariance, after[2], ex.lead)

    def stats(self) -> dict:
        clients = self.server.clients
        ex = self.inspection
        return {"sim_s": round(self.sim_time(), 1), "counters": dict(self.counters),
                "mcu_decoder": self.mcu_decoder.stats.as_dict(),
                "mcu_reports": self.mcu_reports, "mcu_acks": dict(self.mcu_acks),
                "serial_errors": self.serial_errors, "clients": len(clients),
                "rejections": dict(self.rejections), "lease": self.lease_info(),
                "inspection": None if ex is None else CoverageState.NAMES[ex.state],
                "covered": None if ex is None else int(ex.covered.sum()),
                "reachable": None if ex is None else ex.reachable,
                "turns_in_place": None if ex is None else ex.turns,
                "moves": None if ex is None else {
                    "backoffs": ex.moves.backoffs, "steps": ex.moves.steps,
                    "out_of_reach": ex.out_of_reach},
                "edge_seeks": None if ex is None else {
                    "started": ex.seek.seeks, "found": ex.seek.found,
                    "given_up": ex.seek.given_up},
                "sure_ends": None if ex is None or ex.sure is None else {
                    "seeks": ex.sure.ends.seeks, "routes": ex.sure.ends.fixes,
                    "route_cells": ex.sure.ends.fix_cells, "unsure": len(ex.sure.ends.unsure),
                    "taken_back": ex.sure.taken_back},
                "sightings_dropped": self.sightings.dropped,
                "pose_sigma_m": round(self.odom.sigma_m, 3) if math.isfinite(
                    self.odom.sigma_m) else None}
