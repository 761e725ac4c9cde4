"""The robot's navigation stack, one step at a time: localise, perceive, execute.

Shared by the relay (its navigation thread, wall-clock paced, sim-time steps)
and by :mod:`sim_robot.patrol_sim` (tests and the bench, stepped directly):

1. localisation (:mod:`localisation`): the odometry increment predicts, each
   lidar scan is matched to the station map (resources/station) and fused;
   when it is lost the robot stops and an event says so — it never drives on
   a guess. Standing still, it then searches the map around where it lost
   itself (``RobotLocaliser.relocalise``, up to ``RELOC_TRIES`` times,
   ``RELOC_RETRY_S`` apart); found, an event says where and a patrol paused
   for it goes on; not found, it waits for the operator's ``set_pose``,
   which stays the last resort. On its charger (the board reports DOCKED)
   it searches the dock only, whose view alone fits another place too, and it
   stands still there whatever its odometry's speeds say. A search that comes
   due while the robot moves waits ``RELOC_WAIT_S`` for it to stand still,
   then counts as a search that found nothing: every loss episode ends in
   one of the two events, on the retry schedule (the desk soak at 36x: a
   gyro bias of 0.12 rad/s read as turning, and the robot lost on its dock
   waited for stillness for ever, with no event). Scans and odometry
   are put in time order, by their sim-time stamps: a scan newer than the
   last odometry sample waits until the odometry has passed it (the MCU's
   reports lag the lidar by seconds of sim time at a high time scale on a
   busy host), then it is matched from the odometry pose interpolated at its
   time (as a ROS message filter waits for the transform);
2. perception: the same scan, interpreted with the *estimated* pose: returns
   off the static map clustered and tracked (:mod:`tracker`) — never the
   world's list of people;
3. the mission executor (:mod:`patrol`) turns pose, velocity and tracked
   obstacles into a speed command; its speed is capped by how stale the
   control is: the command is held until the next step, so the robot may
   cover at most the room between its body and the map's nearest obstacle
   in the time the recent steps took (``hold_s``: the longest step lately).
   On a starved host the steps come seconds of sim time apart, and a command
   meant for 0.1 s drove blind for seconds.

The world is used for the station's static layout (map, dock, gauges) and by
the lidar sensor (:class:`~sim_robot.lidar.MountedLidar`); the navigation never
reads the robot's true pose (tests/sim/test_localisation_patrol.py guards it).
"""

from __future__ import annotations

import bisect
import math
import time
from collections import deque
from collections.abc import Callable

import cv2
import numpy as np

from app.comm.protocol import MapImage, Pose
from app.core.planner import GridMap

from . import raycast
from .lidar import MountedLidar
from .localisation import RobotLocaliser, load_station_map
from .mapping_mode import warm_up as mapping_warm_up
from .patrol import PAUSED, PatrolConfig, PatrolExecutor
from .tracker import ObstacleTracker
from .world import World

ODOM_HISTORY_S = 10.0  # odometry samples kept to find the pose at a scan's time (sim)
SCAN_WAIT_MAX = 100  # scans waiting for the odometry to pass them (the oldest go first)
LOCALISE_PERIOD_S = 0.2  # scans are matched to the map at most this often (sim time)
TRACK_AHEAD_MAX_S = 1.0  # the estimate is carried ahead of the odometry at most this far
HOLD_MEMORY_S = 5.0  # a long control step is remembered this long (sim), fading
STALE_V_FLOOR_MPS = 0.1  # the staleness cap never slows the robot below this
RELOC_TRIES = 3  # a lost robot searches the map for itself this often, standing still,
RELOC_RETRY_S = 5.0  # ... this far apart (sim time)
RELOC_WAIT_S = 5.0  # a search due while the robot moves waits this long (sim), then fails
STILL_MPS, STILL_RPS = 0.02, 0.02  # the odometry's speeds under which the robot stands still
LOST_PAUSE = "localisation lost"


def map_image(grid: GridMap) -> MapImage:
    """The occupancy grid as a MapImage (PNG, 0 blocked / 255 free, row 0 = north)."""
    img = np.where(np.flipud(grid.blocked), 0, 255).astype(np.uint8)
    ok, png = cv2.imencode(".png", img)
    if not ok:
        raise RuntimeError("PNG encoding of the map failed")
    h, w = grid.blocked.shape
    return MapImage(grid.resolution_m, grid.origin_xy[0], grid.origin_xy[1], w, h,
                    png.tobytes())


class Navigation:
    def __init__(self, world: World, seed: int, emit: Callable[..., None],
                 publish: Callable[[object], None], look_at: Callable[[str | None], None],
                 config: PatrolConfig | None = None, lidar_beams: int = 360,
                 lidar_range_m: float = 12.0,
                 initial_pose: tuple[float, float, float] | None = None,
                 station_map: str | None = None) -> None:
        self.world = world
        self.emit = emit
        blocked, res, origin = world.occupancy_grid()
        self.grid = GridMap(blocked, res, origin)
        d = world.dock
        # the dock's pose, unless the robot was switched on elsewhere (then the
        # caller says where, as an operator would)
        start = initial_pose if initial_pose is not None else (d[0], d[1], d[2])
        loc_map = load_station_map(station_map) if station_map else load_station_map()
        self.localiser = RobotLocaliser(loc_map, start)
        self.lidar = MountedLidar(world, np.random.default_rng(seed + 4000), lidar_beams,
                                  lidar_range_m)
        self._odom_last = None  # (pose, velocity) of the last odometry sample
        self.odom_t: float | None = None  # its sim time (the MCU report's)
        self._odom_hist: deque[tuple[float, float, float, float]] = deque()  # (t, x, y, θ)
        self._scans_waiting: deque[tuple[float, object]] = deque()  # (stamp, LidarScan)
        self.scans_dropped = 0  # scans the odometry never passed (too many waiting)
        self._fused_t: float | None = None  # the stamp of the last scan matched to the map
        self.mapping = None  # a MappingMode while the robot maps (the relay sets it)
        self.lost_reported = False
        self._stop_pending = False
        self._reloc_tries = 0  # searches in this loss episode
        self._reloc_due: float | None = None  # sim time the next one is due (None: at once)
        self.reloc_unsearched = 0  # searches not made: the robot did not stand still
        self._unsearched = 0  # ... in this loss episode
        self.docked = False  # the board reports the robot on its charger (the relay sets it)
        self.scan = None  # the last lidar scan (LidarScan)
        self.tracker = ObstacleTracker(world.clearance_m, res, origin)
        tanks = [(t["x"], t["y"]) for t in world.spec.get("tanks", [])]
        self.executor = PatrolExecutor(self.grid, (d[0], d[1], d[2]),
                                       {g.id: (g.x, g.y) for g in world.gauges}, tanks, emit,
                                       publish, look_at, config)
        self.step_ms: list[float] = []
        self.hold_s = 0.0  # how long a command is held (the recent control steps, sim)
        self.stale_capped = 0  # steps whose speed the staleness cap lowered
        self.obstacles = np.zeros((0, 5))
        self.scan_t: float | None = None

    def warm_up(self) -> None:
        """Run the compiled kernels once (numba cache load) before the first mission
        or mapping session."""
        d = self.world.dock
        hp = self.executor.planner
        hp.plan((d[0], d[1]), (d[0] - 1.0, d[1]))
        hp.step((d[0], d[1], d[2]), (0.0, 0.0), [(d[0] - 3, d[1], 0.1, 0.0, 0.3)], 0.1)
        hp.warm_up()
        hp.set_path([])
        mapping_warm_up()
        raycast.warm_up()  # the lidar's and the board's rangers' ray cast

    def perceive(self, t_s: float) -> np.ndarray:
        """Read the lidar: match the scans the odometry has passed to the map
        (localisation), then track what is not on the map in this scan, seen
        from the estimate carried to its time."""
        scan = self.lidar.read()
        self.scan = scan
        stamp = self.lidar.stamp_s if self.lidar.stamp_s is not None else t_s
        self._scans_waiting.append((stamp, scan))
        if len(self._scans_waiting) > SCAN_WAIT_MAX:
            self._scans_waiting.popleft()
            self.scans_dropped += 1
        self._localise_waiting()
        self._check_lost()
        if not self.localiser.lost:
            det = self.tracker.detect(scan.ranges_m, scan.angle_min_rad,
                                      scan.angle_increment_rad, self._pose_at(stamp))
            self.tracker.update(t_s, det)
            self.obstacles = self.tracker.obstacles()
        self.scan_t = t_s
        return self.obstacles

    def _localise_waiting(self) -> None:
        """Fuse the newest waiting scan that the odometry has passed (older
        ones that also wait are superseded by it; newer ones wait on), at
        most one per ``LOCALISE_PERIOD_S`` of sim time (the tracker reads
        every scan)."""
        if not self._odom_hist:
            return
        t_odom = self._odom_hist[-1][0]
        ready = None
        while self._scans_waiting and self._scans_waiting[0][0] <= t_odom + 1e-6:
            ready = self._scans_waiting.popleft()
        if ready is None:
            return
        stamp, scan = ready
        if self._fused_t is not None and self._fused_t <= stamp < self._fused_t + \
                LOCALISE_PERIOD_S - 1e-6:
            return  # 5 Hz of sim time, however fast the host steps the world
        self._fused_t = stamp
        loc = self.localiser
        fused = loc.scans
        loc.correct(scan, self.obstacles, self._odom_at(stamp))
        if (self.mapping is not None and self.mapping.active and loc.scans > fused
                and loc.scan_odom_pose is not None):
            # a new view only, and without the people and carts the tracker
            # follows: a map keeps walls, not where someone walked by (and
            # the beams that came back with nothing clear where they were)
            self.mapping.add(loc.scan_odom_pose, loc.static_points, loc.map_points(),
                             loc.free_points())

    def _odom_at(self, t: float) -> tuple[float, float, float]:
        """The odometry pose at sim time ``t``, interpolated between its samples
        (the oldest kept for an older ``t``; the newest for a later one)."""
        h = self._odom_hist
        if t >= h[-1][0]:
            return h[-1][1:]
        if t <= h[0][0]:
            return h[0][1:]
        i = bisect.bisect_left(h, (t,))
        (t0, x0, y0, a0), (t1, x1, y1, a1) = h[i - 1], h[i]
        f = (t - t0) / (t1 - t0) if t1 > t0 else 1.0
        da = (a1 - a0 + math.pi) % (2 * math.pi) - math.pi
        return x0 + f * (x1 - x0), y0 + f * (y1 - y0), a0 + f * da

    def _pose_at(self, t: float) -> tuple[float, float, float]:
        """The estimate at sim time ``t``: carried back along the odometry, or
        (a scan the odometry has not reached yet) ahead by its last velocity."""
        loc = self.localiser
        if not self._odom_hist or self._odom_last is None:
            return loc.pose
        t_odom = self._odom_hist[-1][0]
        if t <= t_odom:
            return loc.pose_at(self._odom_at(t))
        ahead = min(t - t_odom, TRACK_AHEAD_MAX_S)
        (x, y, th), (v, w) = self._odom_last
        mid = th + w * ahead / 2
        return loc.pose_at((x + v * ahead * math.cos(mid), y + v * ahead * math.sin(mid),
                            th + w * ahead))

    def _remember_odometry(self, t: float, pose) -> None:
        h = self._odom_hist
        if h and t < h[-1][0] - 1.0:  # the clock went back (a reset MCU): start again
            h.clear()
        if h and t <= h[-1][0]:
            h[-1] = (h[-1][0], *pose)  # the same report again
        else:
            h.append((t, *pose))
        while h[0][0] < t - ODOM_HISTORY_S:
            h.popleft()

    def _check_lost(self) -> None:
        """On losing localisation: stop the mission and tell the operator, once."""
        loc = self.localiser
        if not loc.lost or self.lost_reported:
            return
        self.lost_reported = True
        q = loc.quality
        x, y, th = loc.pose
        self._stop_pending = True
        self._reloc_tries = 0
        self._reloc_due = None
        self._unsearched = 0
        if self.executor.owns_motors:
            self.executor.pause(LOST_PAUSE)
        self.emit("alarm", "localisation_lost",
                  "localisation lost: the robot stopped and searches the station map for "
                  "itself; if it does not find itself, set its pose on the map",
                  x_m=round(x, 3), y_m=round(y, 3), theta_rad=round(th, 4),
                  failures=q.failures_in_row if q else 0,
                  sigma_xy_m=round(q.sigma_xy_m, 3) if q else None)

    def _standing(self) -> bool:
        """The robot stands still: on its charger (the board reports DOCKED
        only at rest there), or by its odometry's speeds."""
        if self.docked:
            return True
        v, w = self._odom_last[1] if self._odom_last is not None else (0.0, 0.0)
        return abs(v) <= STILL_MPS and abs(w) <= STILL_RPS

    def _relocalise(self, t_s: float) -> None:
        """Lost and standing still: search the map for the robot (see the
        module's note); an event either way, once per loss episode."""
        if self._reloc_tries >= RELOC_TRIES:
            return
        if self._reloc_due is None:
            self._reloc_due = t_s  # the first search at once
        if t_s < self._reloc_due - 1e-9:
            return
        found = None
        if self._standing():
            scan = self.lidar.read()
            if self.docked:  # its charging contacts say where: search the dock only
                d = self.world.dock
                found = self.localiser.relocalise(scan, around=(d[0], d[1]), window_m=d[3],
                                                  confined=True)
            else:
                found = self.localiser.relocalise(scan)
        elif t_s - self._reloc_due < RELOC_WAIT_S:
            return  # wait a while for it to stand still
        else:
            self.reloc_unsearched += 1
            self._unsearched += 1
        self._reloc_tries += 1
        self._reloc_due = t_s + RELOC_RETRY_S
        if found is None:
            if self._reloc_tries >= RELOC_TRIES:
                moving = (f", {self._unsearched} not made: it did not stand still"
                          if self._unsearched else "")
                self.emit("alarm", "relocalisation_failed",
                          f"the robot did not find itself on the station map ({RELOC_TRIES} "
                          f"searches{moving}); set its pose on the map to go on",
                          tries=RELOC_TRIES, unsearched=self._unsearched)
            return
        (x, y, th), inliers = found
        self.lost_reported = False
        ex = self.executor
        resume = ex.state == PAUSED and ex.reason == LOST_PAUSE
        self.emit("warning", "localisation_recovered",
                  f"localisation recovered: the robot found itself on the station map at "
                  f"({x:.2f}, {y:.2f}, {math.degrees(th):.0f}°), {inliers:.0%} of its scan "
                  "on the map" + ("; the patrol goes on" if resume else ""),
                  x_m=round(x, 3), y_m=round(y, 3), theta_rad=round(th, 4),
                  inlier_fraction=round(inliers, 3), tries=self._reloc_tries)
        if resume:
            ex.resume()

    def set_pose(self, x: float, y: float, theta: float) -> None:
        """The operator's pose (``set_pose``): localisation starts again from it."""
        was_lost = self.localiser.lost
        self.localiser.set_pose(x, y, theta, sigma_xy_m=0.25, sigma_theta_rad=math.radians(8))
        self.lost_reported = False
        self.emit("info", "pose_set", f"pose set by the operator to ({x:.2f}, {y:.2f}, "
                  f"{math.degrees(theta):.0f}°)" + (" — localisation restored" if was_lost else ""),
                  x_m=x, y_m=y, theta_rad=theta, was_lost=was_lost)

    def pose_message(self, v_mps: float, omega_rps: float) -> Pose:
        """The published pose: the estimate and its quality (never the truth)."""
        loc = self.localiser
        x, y, th = loc.pose
        p = loc.covariance
        q = loc.quality
        status = Pose.STATUS_LOST if loc.lost else Pose.STATUS_TRACKING
        return Pose(x, y, th, v_mps, omega_rps, float(p[0, 0]), float(p[0, 1]), float(p[1, 1]),
                    float(p[2, 2]), float(q.inlier_fraction) if q else 0.0,
                    float(q.rmse_m) if q and math.isfinite(q.rmse_m) else 0.0, status)

    def step(self, t_s: float, dt: float, odom_xytheta: tuple[float, float, float],
             odom_velocity: tuple[float, float] = (0.0, 0.0),
             odom_t_s: float | None = None,
             odom_trail: list[tuple[float, float, float, float]] | None = None
             ) -> tuple[float, float, bool]:
        """Localise (odometry prediction; a scan while a mission owns the
        motors), perceive, decide. Lost: stop, whatever the mission wanted.
        ``odom_trail``: the odometry samples (t, x, y, θ) since the last step,
        when several arrived (the pose at a scan's time is interpolated
        between them)."""
        t0 = time.perf_counter()
        loc = self.localiser
        loc.predict(odom_xytheta, odom_velocity)
        self._odom_last = (tuple(odom_xytheta), tuple(odom_velocity))
        self.odom_t = t_s if odom_t_s is None else odom_t_s
        for ts, x, y, th in odom_trail or ():  # the samples since the last step
            self._remember_odometry(ts, (x, y, th))
        self._remember_odometry(self.odom_t, odom_xytheta)
        ex = self.executor
        if ex.owns_motors:
            self.perceive(t_s)
        if loc.lost:
            self._check_lost()
            # one stop command; then the motors are the operator's (driving by
            # hand is allowed, missions are refused until the pose is set)
            stop, self._stop_pending = self._stop_pending, False
            if not stop:
                self._relocalise(t_s)
            return 0.0, 0.0, stop
        # the estimate carried to now: the odometry may be late (see _pose_at)
        vel = (loc.v, loc.omega)
        pose = self._pose_at(t_s)
        v, w, send = ex.tick(t_s, dt, pose, vel, self.obstacles)
        if send and ex.owns_motors:
            v = self._stale_cap(v, dt, pose)
            ex.last_cmd = (v, w)
            self.step_ms.append((time.perf_counter() - t0) * 1000.0)
        return v, w, send

    def _stale_cap(self, v: float, dt: float, pose) -> float:
        """``v`` no faster than the room around the body (by the map) allows
        in the time a command is held (see the module's note)."""
        h = self.hold_s
        self.hold_s = max(dt, h + (dt - h) * min(1.0, dt / HOLD_MEMORY_S))
        room = max(self.executor.recovery.clearance_m(pose[0], pose[1]), 0.0)
        cap = max(room / max(self.hold_s, 1e-3), STALE_V_FLOOR_MPS)
        if abs(v) <= cap:
            return v
        self.stale_capped += 1
        return math.copysign(cap, v)
