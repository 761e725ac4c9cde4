"""The pan-tilt-zoom inspection view: what the camera head sees when aimed at a gauge.

The head sits on a mast at ``PTZ_HEIGHT_M`` and zooms so the dial fills about 0.5-0.7 of
the frame's shorter side.  The dial (drawn by :mod:`sim_robot.gauge_render` at the gauge's
true value) is seen through a pinhole homography whose tilt follows the relative geometry of
the robot and the gauge's facing, plus a small rotation of the gauge in its mounting (fixed
per gauge id).  Lighting follows the station's time of day; glare comes and goes; sensor
noise is always there and the image smears while the robot moves.

Costly pieces are cached: the dial per (gauge, value to 0.1 % FS), the background panel per
gauge, the dial's mask per size and a few noise frames.  Qt-free (numpy + OpenCV).
"""

from __future__ import annotations

import logging
import math
import zlib
from dataclasses import dataclass

import cv2
import numpy as np

from . import gauge_render
from .world import Gauge, World

log = logging.getLogger(__name__)

__all__ = ["PTZ_HEIGHT_M", "PtzGeometry", "PtzView", "mount_roll_deg", "ptz_geometry"]

PTZ_HEIGHT_M = 1.1  # the head's height on its mast
FOCAL_PX = 1400.0  # a long (zoomed) lens: weak perspective
MAX_TILT_DEG = 70.0
VALUE_STEPS = 1000  # the dial is redrawn when the value moves by 0.1 % FS


def mount_roll_deg(gauge_id: str) -> float:
    """The gauge's rotation in its mounting, in [-8, 8] degrees, fixed per id."""
    h = zlib.crc32(gauge_id.encode("utf-8")) & 0xFFFF
    return (h / 0xFFFF - 0.5) * 16.0


@dataclass(frozen=True)
class PtzGeometry:
    """How the dial is seen from the head: tilt (deg) about an in-plane axis, roll (deg),
    distance (m), whether its face is towards the camera, and the zoom's fill."""

    tilt_deg: float
    tilt_axis_deg: float
    roll_deg: float
    distance_m: float
    visible: bool
    fill: float


def ptz_geometry(g: Gauge, x: float, y: float) -> PtzGeometry:
    """Tilt and roll of the dial seen from a head at (x, y, PTZ_HEIGHT_M).

    The view ray from the gauge to the head, in the dial's own frame: ``yaw`` is the
    horizontal angle between the dial's normal (``facing_rad``) and that ray, ``pitch`` its
    elevation.  A yaw turns the dial about its vertical axis (tilt axis 90 deg), a pitch about
    its horizontal axis (0 deg); the combined rotation vector gives tilt and axis.
    """
    dx, dy = x - g.x, y - g.y
    horiz = math.hypot(dx, dy)
    dz = PTZ_HEIGHT_M - g.height_m
    dist = math.hypot(horiz, dz)
    to_cam = math.atan2(dy, dx)
    yaw = (to_cam - g.facing_rad + math.pi) % (2 * math.pi) - math.pi
    pitch = math.atan2(dz, max(horiz, 1e-6))
    visible = abs(yaw) < math.radians(80.0) and horiz > 0.2
    yaw_d, pitch_d = math.degrees(yaw), math.degrees(pitch)
    tilt = min(MAX_TILT_DEG, math.hypot(yaw_d, pitch_d))
    axis = math.degrees(math.atan2(yaw_d, pitch_d))
    fill = float(np.clip(0.7 - 0.04 * max(0.0, dist - 1.0), 0.5, 0.7))
    return PtzGeometry(tilt, axis, mount_roll_deg(g.id), dist, visible, fill)


def _rotation(tilt_deg: float, tilt_axis_deg: float, roll_deg: float) -> np.ndarray:
    ax = math.radians(tilt_axis_deg)
    rv = np.array([math.cos(ax), math.sin(ax), 0.0]) * math.radians(tilt_deg)
    r_tilt, _ = cv2.Rodrigues(rv)
    r_roll, _ = cv2.Rodrigues(np.array([0.0, 0.0, math.radians(roll_deg)]))
    return r_roll @ r_tilt


def daylight_gain(world: World, t_s: float) -> float:
    """Scene brightness from the time of day: 1.05 at noon, 0.55 at night (floodlights)."""
    tod_h = world.time_of_day_s(t_s) / 3600.0
    sun = max(0.0, math.sin(math.pi * (tod_h - 6.0) / 12.0))
    return 0.55 + 0.5 * sun


class PtzView:
    """Renders the inspection view of one gauge; ``render(...)`` -> 640 x 480 BGR uint8."""

    def __init__(self, world: World, width: int = 640, height: int = 480,
                 seed: int = 0) -> None:
        self.world = world
        self.w, self.h = width, height
        self.rng = np.random.default_rng(seed)
        self._dial: tuple[tuple, np.ndarray] | None = None
        self._backgrounds: dict[str, np.ndarray] = {}
        self._masks: dict[int, np.ndarray] = {}
        self._glare_grid: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self._noise = []
        for _ in range(4):
            n = np.empty((height, width, 3), np.int16)
            cv2.randn(n, 0, 3.0)
            self._noise.append(n)
        self._last_pose: tuple[float, float, float, float] | None = None
        self.frames = 0

    # ------------------------------------------------------------ cached pieces
    def _spec(self, g: Gauge) -> gauge_render.GaugeSpec | None:
        try:
            return gauge_render.stock_spec(g.type)
        except KeyError:
            return None

    def _dial_img(self, g: Gauge, spec, value: float, size: int) -> np.ndarray:
        q = int(round((value - g.min) / (g.max - g.min) * VALUE_STEPS))
        key = (g.id, q, size)
        if self._dial is None or self._dial[0] != key:
            qv = g.min + q / VALUE_STEPS * (g.max - g.min)
            self._dial = (key, gauge_render.render_dial(spec, qv, size))
        return self._dial[1]

    def _background(self, g: Gauge) -> np.ndarray:
        bg = self._backgrounds.get(g.id)
        if bg is None:
            bg = _panel_background(self.w, self.h, zlib.crc32(g.id.encode("utf-8")))
            self._backgrounds[g.id] = bg
        return bg

    def _mask(self, size: int) -> np.ndarray:
        m = self._masks.get(size)
        if m is None:
            m = np.zeros((size, size), np.uint8)
            sc = 16
            cv2.circle(m, (int(size / 2 * sc), int(size / 2 * sc)), int(0.49 * size * sc), 255,
                       -1, cv2.LINE_AA, 4)
            self._masks[size] = m
        return m

    def _glare(self, dial: np.ndarray, g: Gauge, t_s: float, gain: float) -> np.ndarray:
        """Occasional glare: on for a while, off for a while, its spot fixed per episode."""
        episode = int(t_s // 20.0)
        r = np.random.default_rng((zlib.crc32(g.id.encode("utf-8")), episode))
        if r.random() > 0.35:
            return dial
        size = dial.shape[0]
        strength = float(r.uniform(0.2, 0.5)) * min(1.0, gain)
        ga = r.uniform(0, 2 * math.pi)
        d = r.uniform(0.05, 0.3) * size
        c = size / 2.0
        gx, gy = c + d * math.cos(ga), c + d * math.sin(ga)
        sx, sy = r.uniform(0.06, 0.14, 2) * size
        th = r.uniform(0, math.pi)
        grid = self._glare_grid.get(size)
        if grid is None:
            yy, xx = np.mgrid[0:size, 0:size].astype(np.float32)
            inside = (np.hypot(xx - c, yy - c) < 0.47 * size).astype(np.float32)
            grid = (xx, yy, inside)
            self._glare_grid[size] = grid
        xx, yy, inside = grid
        u = (xx - gx) * math.cos(th) + (yy - gy) * math.sin(th)
        v = -(xx - gx) * math.sin(th) + (yy - gy) * math.cos(th)
        alpha = (strength * np.exp(-0.5 * ((u / sx) ** 2 + (v / sy) ** 2)) * inside)
        a3 = cv2.merge([alpha, alpha, alpha])
        out = dial.astype(np.float32) * (1 - a3) + 255.0 * a3
        return out.astype(np.uint8)

    # ------------------------------------------------------------ frame
    def render(self, g: Gauge, x: float, y: float, theta: float, t_s: float) -> np.ndarray:
        """The head's view of gauge ``g`` from the robot at (x, y, theta) at sim time t_s."""
        self.frames += 1
        speed_px = self._motion_px(x, y, theta, t_s)
        geo = ptz_geometry(g, x, y)
        spec = self._spec(g)
        gain = daylight_gain(self.world, t_s)
        frame = self._background(g).copy()
        if spec is not None and geo.visible:
            self._draw_gauge(frame, g, spec, geo, t_s, gain)
        elif geo.visible:  # a gauge type the renderer does not know: a plain dial
            from .camera import draw_simple_dial

            dial = draw_simple_dial(g.min, g.max, g.value(t_s), g.unit, 300)
            self._paste_centre(frame, dial)
        else:  # the back of the gauge: a grey disc on its post
            cv2.circle(frame, (self.w // 2, self.h // 2), int(0.3 * self.h), (95, 95, 100), -1,
                       cv2.LINE_AA)
        if abs(gain - 1.0) > 0.01:
            frame = cv2.convertScaleAbs(frame, alpha=gain)
        if speed_px >= 1.5:
            n = int(min(15, round(speed_px)))
            kern = np.zeros((1, n), np.float32)
            kern[:] = 1.0 / n
            frame = cv2.filter2D(frame, -1, kern)
        noise = self._noise[self.frames % len(self._noise)]
        return cv2.add(frame, noise, dtype=cv2.CV_8U)

    def _motion_px(self, x: float, y: float, theta: float, t_s: float) -> float:
        """Image smear in pixels over one exposure, from how far the robot moved since the
        previous frame (the head keeps the dial centred, so only part of it remains)."""
        last, self._last_pose = self._last_pose, (x, y, theta, t_s)
        if last is None:
            return 0.0
        dt = t_s - last[3]
        if not 1e-3 < dt < 1.0:
            return 0.0
        v = math.hypot(x - last[0], y - last[1]) / dt
        w = abs((theta - last[2] + math.pi) % (2 * math.pi) - math.pi) / dt
        exposure_s = 0.02
        return (v * 40.0 + w * 120.0) * exposure_s * 10.0

    def _draw_gauge(self, frame: np.ndarray, g: Gauge, spec, geo: PtzGeometry, t_s: float,
                    gain: float) -> None:
        short = min(self.w, self.h)
        size = int(round(geo.fill * short / 0.98))
        size += size % 2
        dial = self._dial_img(g, spec, g.value(t_s), size)
        dial = self._glare(dial, g, t_s, gain)
        c = size / 2.0
        rot = _rotation(geo.tilt_deg, geo.tilt_axis_deg, geo.roll_deg)
        k = np.array([[FOCAL_PX, 0, self.w / 2], [0, FOCAL_PX, self.h / 2], [0, 0, 1.0]])
        t = np.array([0.0, 0.0, FOCAL_PX])
        hmat = k @ np.column_stack([rot[:, 0], rot[:, 1], t]) @ np.array(
            [[1, 0, -c], [0, 1, -c], [0, 0, 1.0]])
        # the post below the dial
        p = hmat @ np.array([c, size * 0.97, 1.0])
        bx, by = p[0] / p[2], p[1] / p[2]
        stem = max(6, int(0.12 * size))
        cv2.rectangle(frame, (int(bx - stem / 2), int(by - 5)), (int(bx + stem / 2), self.h),
                      (90, 110, 140), -1)
        # warp only the dial's bounding box of the frame
        corners = np.array([[0, 0, 1], [size, 0, 1], [0, size, 1], [size, size, 1]], float).T
        pc = hmat @ corners
        pc = pc[:2] / pc[2]
        x0 = max(0, int(math.floor(pc[0].min())) - 2)
        y0 = max(0, int(math.floor(pc[1].min())) - 2)
        x1 = min(self.w, int(math.ceil(pc[0].max())) + 2)
        y1 = min(self.h, int(math.ceil(pc[1].max())) + 2)
        if x1 <= x0 or y1 <= y0:
            return
        hroi = np.array([[1, 0, -x0], [0, 1, -y0], [0, 0, 1.0]]) @ hmat
        warped = cv2.warpPerspective(dial, hroi, (x1 - x0, y1 - y0), flags=cv2.INTER_LINEAR)
        wm = cv2.warpPerspective(self._mask(size), hroi, (x1 - x0, y1 - y0),
                                 flags=cv2.INTER_LINEAR)
        a = wm.astype(np.float32) * (1.0 / 255.0)
        roi = frame[y0:y1, x0:x1]
        frame[y0:y1, x0:x1] = cv2.blendLinear(warped, roi, a, 1.0 - a)

    def _paste_centre(self, frame: np.ndarray, dial: np.ndarray) -> None:
        h, w = dial.shape[:2]
        y0, x0 = (self.h - h) // 2, (self.w - w) // 2
        frame[y0:y0 + h, x0:x0 + w] = dial


def _panel_background(w: int, h: int, seed: int) -> np.ndarray:
    """A plant-room wall behind the gauge: a painted panel, a pipe or two, a label."""
    r = np.random.default_rng(seed)
    base = r.uniform(70, 170, 3)
    grad = np.linspace(0.8, 1.1, h, dtype=np.float32)[:, None, None]
    img = np.broadcast_to(base[None, None, :] * grad, (h, w, 3)).astype(np.float32).copy()
    for _ in range(int(r.integers(1, 3))):  # horizontal pipes with cylindrical shading
        t = int(r.integers(30, 70))
        col = r.uniform(60, 220, 3)
        prof = (0.45 + 0.75 * np.cos(np.linspace(-1.3, 1.3, t)) ** 2)[:, None] * col[None, :]
        y0 = int(r.choice([r.integers(0, h // 6), r.integers(5 * h // 6, h - t // 2)]))
        ys = np.arange(y0, y0 + t)
        ok = ys < h
        img[ys[ok], :, :] = np.clip(prof[ok], 0, 255)[:, None, :]
    img = np.clip(img, 0, 255).astype(np.uint8)
    x0 = int(r.integers(10, w // 5))
    cv2.rectangle(img, (x0, 20), (x0 + 90, 48), (235, 235, 235), -1)
    cv2.putText(img, f"PT-{int(r.integers(0, 999)):03d}", (x0 + 6, 42),
                cv2.FONT_HERSHEY_SIMPLEX, 0.6, (20, 20, 20), 2)
    return img
