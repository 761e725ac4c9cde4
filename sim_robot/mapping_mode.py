"""Mapping mode: the operator drives the robot round the station by keyboard
and the map grows from its scans (seed 002 §2.3's laser landmarks, with loop
closure: app/core/localisation/mapping.py's ``LaserMapper``).

The navigation hands each lidar scan (pre-processed) with the odometry pose
to :meth:`MappingMode.add`; the relay publishes the map every few seconds so
the desk watches it grow (drawn from every scan kept while the robot moved,
each at its mapper node's current pose, so the whole map follows a loop
closure; unknown cells grey; taken as a :meth:`view` under
the relay's lock, drawn on a thread of its own, since drawing a station-sized
map costs about a second of CPU), and
``save_map`` writes it in the ROS map_server format (YAML + PGM, unknown cells
kept unknown) under the robot's maps folder. The saved map is the finished
one: the mapper's ``finish()`` (the final pass and the edge classes'
variance components, a few seconds of CPU once per map) runs on a :meth:`snapshot`, a copy
taken at the save, so the caller can run it off the relay's lock and the
robot maps on meanwhile (the relay saves on a thread of its own). The mapper works in the frame of
its first scan; the map is carried into the odometry's frame by that scan's
odometry pose (the odometry starts at the pose the robot was switched on at,
the dock), so a map made from the dock lines up with the station's.
"""

from __future__ import annotations

import copy
import logging
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from app.comm.protocol import MapImage
from app.core.localisation.loop_closure import LoopConfig
from app.core.localisation.map_io import FREE, OCCUPIED, OccupancyGrid, build_grid, save_map
from app.core.localisation.mapping import LaserMapper, MappingConfig
from app.core.localisation.se2 import compose, relative, wrap
from app.core.mapimage import BLOCKED, UNKNOWN
from app.core.mapimage import FREE as PNG_FREE

log = logging.getLogger(__name__)

NAME_RE = re.compile(r"^[A-Za-z0-9_-]{1,40}$")

# The mapper (mapping.py) was made on lidar logs whose scans are about 1 m and
# up to 80° of turn apart, each a keyframe. The station lidar comes at 5 Hz,
# 0.1 m apart at walking pace: fed every scan with the logs' 0.4 m keyframe
# spacing, each metre of path chained 2-3 keyframe matches (their errors add
# up round a lap) and every 0.1 m step became a graph edge with the edge floor
# of a 1 m step (a lap's chain too soft for a loop closure to bend right).
# Mapping mode therefore hands the mapper a scan only when the odometry has
# moved ``SCAN_EVERY_M`` or turned ``SCAN_EVERY_RAD`` since the last one, and
# keyframes as far apart as on the logs.
SCAN_EVERY_M = 0.25
SCAN_EVERY_RAD = math.radians(10)
# The station's walls are thin (a few decimetres) and the route passes both
# sides of some: a loop-closure match of a scan from one side against
# keyframes from the other paired the two faces and closed the loop 0.4 m
# off across the wall (right after the robot turned on the spot at a
# waypoint and drove off along the road beside it); the pose graph then
# bent the soft stretch of the turn to meet it. The references therefore
# know which side each wall point was seen from (MappingConfig.faces).
# The map is drawn from every scan offered while the robot moves, not only
# the mapper's keyframes (whose views alone miss far walls that other scans
# saw): each is kept relative to the mapper's latest node by the odometry
# between them, so it moves with that node's solved pose. A scan is kept when
# the robot moved ``KEEP_EVERY_M`` or turned ``KEEP_EVERY_RAD`` since the last
# kept one; beyond ``MAX_KEPT`` scans (about 15 MB) every other one between
# nodes is dropped, so a long session's memory stays bounded. Each kept scan
# also keeps the free rays of its beams that returned nothing
# (app/core/localisation/free_space.py, as float16 ends, up to 17 MB more
# where most beams see open ground: a cart that drove off 8-12 m away, seen
# only against open ground, is cleared by them).
KEEP_EVERY_M = 0.05
KEEP_EVERY_RAD = math.radians(3)
MAX_KEPT = 12000
# The map is a counting map (map_io.build_grid): a cell is occupied when
# l_occ · hits + l_free · misses > 0.5. With the logs' −0.6 (a cell is a wall
# while hits make up more than 40 % of the beams that end in or cross it) a
# wall seen at a grazing angle was worn away: at 0.1 m cells, beams that end
# farther along a wall pass through the corners of its nearer cells more
# often than beams end in them (a wall 1 m beside a 1 m drive lost a third of
# its cells 2-10 m ahead: tests/sim/test_mapping_mode.py; on the mapping
# bench, most where the grid's cells lay half a cell off the walls:
# bench/mapping_mode_bench.py's docstring). ``MAP_L_FREE`` puts
# the share at GMapping's occupancy threshold (occ_thresh 0.25): −0.3. A
# transient object needs misses three times its hits to go, which the
# kept scans' many beams across a place it left (no-return ones included)
# give; a free cell needs two misses and no hit.
MAP_L_FREE = -0.3
# Even so, where a wall's face fell inside its cells rather than on their
# edge (a real map's walls fall anywhere in its cells), the beams that end
# farther along a wall seen at a grazing angle still ran through the near
# half of its face cells on their last decimetres and wore them away; each
# return's free ray therefore stops a cell off the surface it ended on, not
# a cell short along the ray (map_io.build_grid's ``stop_at_surface``).
MAP_STOP_AT_SURFACE = True
# A lap's closures are few (the route's middle is closed only at its two
# ends), so where the chain's heading error sits decides the map: a match
# whose ICP and grid fits part is less sure by their disagreement
# (MappingConfig.match_disagreement_k), and the edges' heading floor is that
# of a 0.25 m step (0.2°; the logs' 0.5° is for 1 m steps), so the fused
# steps' own covariances, not the floor, say which steps are less sure
# (bench/mapping_mode_bench.py's docstring: the floor alone did not help).
# The logs' default weighs the two fits as two hypotheses ("mixture",
# match_mixture.py); the station keeps the grid fit ("fusion"), with which
# its k was chosen: the mixture was not measured on the station's maps.
# The saved map is the finished one, and finishing it matters: the chain's
# matches each err about 0.04° in heading (against keyframes at their true
# poses as much: the lidar's 1.5 cm noise), the map's heading relative to its
# first scan walks with the keyframes handed on from one to the next, and a
# lap's loop ties its end only to its start, so a whole lap's map came out
# turned by up to 0.13° about the dock (seed 1: 7 cm median pose error, 1.8
# cm once turned back; bench/mapping_mode_bench.py's docstring). The final
# pass (loop_closure.py) matches every keyframe again against the older
# places within 10 m that it overlaps, so the dock's view and every stretch
# seen twice tie the map directly, and the edge classes' variance components
# (variance_components.py) weigh those edges against the chain by their
# residuals. It matches as the online closures do: by ICP, against
# references that know each wall's faces, a direction few inlier pairs hold
# left free (``final_free_directions``). With the logs' grid fit, whose
# covariance stated 8-16 cm along a road however free the road left it, a
# tenth of its edges held the solution's own error along the roads (10-30
# cm off) and the maps broke (coverage 78-94 %). The long-range ties stay
# off: with them the maps broke too (23-46 cm median pose error; not
# looked into).
MAPPING_CONFIG = MappingConfig(landmark_dist_m=1.0, landmark_angle_rad=math.radians(30),
                               faces=True, edge_floor_theta_rad=math.radians(0.2),
                               match_disagreement="fusion", final_pass=True,
                               long_range=False,
                               loop=LoopConfig(final_matcher="icp",
                                               final_free_directions=True))


@dataclass(frozen=True)
class KeptScan:
    """A scan for the map: its points (sensor frame, float32), the ends of
    the free rays of its beams that returned nothing (float16), and its pose
    relative to mapper node ``node`` (by the odometry between them)."""

    node: int
    rel: np.ndarray
    points: np.ndarray
    free: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.float16))


@dataclass
class MapSnapshot:
    """A copy of the mapper at one moment, with the odometry pose of its first
    scan and the scans kept for the map."""

    mapper: LaserMapper
    anchor: np.ndarray
    resolution_m: float
    kept: list[KeptScan] = field(default_factory=list)

    def finish(self) -> OccupancyGrid:
        """The final solve (seconds of CPU; the live mapper is untouched), then the grid."""
        self.mapper.finish()
        return _view(self.mapper, self.anchor, self.resolution_m, self.kept).grid()


@dataclass
class MapView:
    """The landmark poses (odometry frame) and their scans at one moment:
    cheap to take under the relay's lock; the grid and the image, which cost
    a second of CPU on a station-sized map, are made from it anywhere."""

    poses: np.ndarray
    scans: list[np.ndarray]  # the landmarks' own arrays (never changed in place)
    resolution_m: float
    free: list[np.ndarray] | None = None  # per scan, its no-return rays' ends

    def grid(self) -> OccupancyGrid:
        return build_grid(self.poses, self.scans, self.resolution_m, l_free=MAP_L_FREE,
                          free_scans=self.free, stop_at_surface=MAP_STOP_AT_SURFACE)

    def image(self) -> MapImage:
        """The map as the desk's MapImage (PNG: 0 occupied, 205 unknown,
        255 free; row 0 = north)."""
        import cv2

        g = self.grid()
        img = np.full(g.cells.shape, UNKNOWN, np.uint8)
        img[g.cells == FREE] = PNG_FREE
        img[g.cells == OCCUPIED] = BLOCKED
        ok, png = cv2.imencode(".png", np.flipud(img))
        if not ok:
            raise RuntimeError("PNG encoding of the map failed")
        h, w = img.shape
        return MapImage(g.resolution_m, float(g.origin_xy[0]), float(g.origin_xy[1]), w, h,
                        png.tobytes())


def _view(m: LaserMapper, anchor: np.ndarray, resolution_m: float,
          kept: list[KeptScan]) -> MapView:
    """The kept scans at their nodes' current poses (the landmarks' scans
    when none were kept)."""
    if not kept:
        poses = np.array([compose(anchor, m.poses[lm.node]) for lm in m.landmarks])
        return MapView(poses, [lm.points for lm in m.landmarks], resolution_m)
    nodes = np.array([k.node for k in kept])
    rel = np.array([k.rel for k in kept])
    return MapView(_compose_many(_compose_many(anchor[None, :], np.array(m.poses)[nodes]), rel),
                   [k.points for k in kept], resolution_m, [k.free for k in kept])


def _compose_many(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise a ⊕ b of (N, 3) (or (1, 3)) poses (se2.compose, vectorised)."""
    c, s = np.cos(a[:, 2]), np.sin(a[:, 2])
    return np.column_stack((a[:, 0] + c * b[:, 0] - s * b[:, 1],
                            a[:, 1] + s * b[:, 0] + c * b[:, 1],
                            wrap(a[:, 2] + b[:, 2])))


def _moved(a: np.ndarray | None, b: np.ndarray, dist_m: float, turn_rad: float) -> bool:
    """Whether odometry pose ``b`` is ``dist_m`` or ``turn_rad`` from ``a`` (or ``a`` is None)."""
    if a is None:
        return True
    return bool(np.hypot(*(b[:2] - a[:2])) >= dist_m or abs(wrap(float(b[2] - a[2]))) >= turn_rad)


def warm_up() -> None:
    """Run the mapper's compiled kernels once (the matching, the covariance,
    the grid), on a made-up oval room. The relay does this before it serves
    (:meth:`sim_robot.navigation.Navigation.warm_up`): on a first run they
    compile, tens of seconds of CPU, and left to the first scans after
    ``start_mapping`` that ran on the navigation thread with the relay's lock
    held: no navigation step, no keep-alive to the MCU (its link watchdog
    stopped the motors) and no growing map for as long."""
    m = MappingMode(Path("."))  # nothing is saved
    m.start()
    ang = np.linspace(-np.pi, np.pi, 360, endpoint=False)
    room = np.column_stack((4 * np.cos(ang), 3 * np.sin(ang)))
    for k in range(4):  # a scan per 0.3 m and 1°: matched against the ones before
        m.add((0.3 * k, 0.0, math.radians(k)), room)
    m.view().grid()


class MappingMode:
    def __init__(self, maps_dir: str | Path, resolution_m: float = 0.1) -> None:
        self.maps_dir = Path(maps_dir)
        self.resolution_m = resolution_m
        self.mapper: LaserMapper | None = None
        self.anchor: np.ndarray | None = None  # the first scan's odometry pose
        self.scans = 0

    @property
    def active(self) -> bool:
        return self.mapper is not None

    def start(self) -> None:
        self.mapper = LaserMapper(MAPPING_CONFIG)
        self.anchor = None
        self.scans = 0
        self._last_odom: np.ndarray | None = None  # of the last scan handed to the mapper
        self.kept: list[KeptScan] = []  # the scans the map is drawn from
        self._kept_odom: np.ndarray | None = None  # ...the last one's odometry pose
        log.info("mapping started")

    def stop(self) -> None:
        """Stop mapping; what was not saved is dropped (no final solve: nothing keeps it)."""
        self.mapper = None
        log.info("mapping stopped after %d scans", self.scans)

    def add(self, odom_pose, points: np.ndarray, map_points: np.ndarray | None = None,
            free_points: np.ndarray | None = None) -> None:
        """Offer one scan (sensor-frame points) taken at ``odom_pose``; it is
        mapped only when the robot moved or turned enough since the last one.
        ``map_points``: the same scan for the occupancy grid, when it keeps
        more than the matching does (RobotLocaliser.map_points); default ``points``.
        ``free_points``: the ends of the free rays of the scan's beams that
        returned nothing (RobotLocaliser.free_points), drawn as free space."""
        if self.mapper is None or len(points) < 20:
            return
        odom = np.asarray(odom_pose, float)
        drawn = points if map_points is None else map_points
        free = np.zeros((0, 2)) if free_points is None else free_points
        if self._last_odom is not None and not _moved(self._last_odom, odom, SCAN_EVERY_M,
                                                      SCAN_EVERY_RAD):
            self._keep(odom, drawn, free)
            return
        if self.anchor is None:
            self.anchor = odom
        self._last_odom = odom
        self.mapper.add_scan(odom, points)
        self.scans += 1
        self._keep(odom, drawn, free, node=True)

    def _keep(self, odom: np.ndarray, points: np.ndarray, free: np.ndarray,
              node: bool = False) -> None:
        """Keep a scan for the map, relative to the mapper's latest node."""
        if not node and not _moved(self._kept_odom, odom, KEEP_EVERY_M, KEEP_EVERY_RAD):
            return
        k = len(self.mapper.poses) - 1
        rel = np.zeros(3) if node else relative(self._last_odom, odom)
        self.kept.append(KeptScan(k, rel, np.asarray(points, np.float32),
                                  np.asarray(free, np.float16).reshape(-1, 2)))
        self._kept_odom = odom
        if len(self.kept) > MAX_KEPT:  # every other scan between nodes goes
            between = [i for i, s in enumerate(self.kept) if s.rel.any()]
            drop = set(between[::2])
            self.kept = [s for i, s in enumerate(self.kept) if i not in drop]

    def grid(self) -> OccupancyGrid | None:
        """The map so far at the live landmark poses (what the desk watches grow)."""
        if self.mapper is None or not self.mapper.landmarks:
            return None
        return self.view().grid()

    def view(self) -> MapView | None:
        """The map so far, to render apart (None before the first landmark)."""
        if self.mapper is None or not self.mapper.landmarks:
            return None
        return _view(self.mapper, self.anchor, self.resolution_m, self.kept)

    def snapshot(self) -> MapSnapshot | None:
        """A copy of the mapper to finish and save apart (None before the first landmark)."""
        if self.mapper is None or not self.mapper.landmarks:
            return None
        return MapSnapshot(copy.deepcopy(self.mapper), self.anchor.copy(), self.resolution_m,
                           list(self.kept))

    def check_name(self, name: str) -> str:
        if not NAME_RE.match(name or ""):
            raise ValueError("a map name is 1-40 letters, digits, '-' or '_'")
        return name

    def map_image(self) -> MapImage | None:
        """The map so far as the desk's MapImage (see :meth:`MapView.image`)."""
        v = self.view()
        return None if v is None else v.image()

    def save(self, name: str, grid: OccupancyGrid | None = None) -> Path:
        """Write ``grid`` (default: the map so far, finished here, which takes
        seconds) as maps_dir/NAME.yaml + NAME.pgm."""
        self.check_name(name)
        if grid is None:
            snap = self.snapshot()
            if snap is None:
                raise ValueError("no map yet: start mapping and drive first")
            grid = snap.finish()
        self.maps_dir.mkdir(parents=True, exist_ok=True)
        return save_map(grid, self.maps_dir / f"{self.check_name(name)}.yaml")
