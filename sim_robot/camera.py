"""The robot's front camera: a cheap ray-cast view of the station, JPEG encoded.

One ray per 4-pixel column finds the nearest obstacle and the nearest *tall*
one (so tanks show above a low bund wall); each becomes a shaded vertical band
whose height follows from the distance (pinhole model, focal length ``f``).
The floor is a road/gravel pattern projected per pixel. Pointer gauges in view
are drawn on their posts with :mod:`sim_robot.gauge_render` when it is
available, else with a simple dial drawn here.

When the pan-tilt head has a target gauge (:meth:`Camera.set_target`), the frame is the
zoomed inspection view of that dial instead (:mod:`sim_robot.ptz`).
"""

from __future__ import annotations

import logging
import math
import time

import cv2
import numpy as np

from .world import Gauge, World

log = logging.getLogger(__name__)

try:  # owned by another module; optional
    from . import gauge_render as _gauge_render  # type: ignore[attr-defined]
except ImportError:  # pragma: no cover - depends on the checkout
    _gauge_render = None

COL_STEP = 4
CAM_HEIGHT_M = 0.6
SKY_TOP = np.array([200, 150, 90], np.float32)  # BGR
SKY_HORIZON = np.array([235, 215, 190], np.float32)
GRAVEL = np.array([120, 135, 140], np.float32)
ROAD = np.array([85, 85, 88], np.float32)
FOG_M = 70.0
DIAL_PX = 200  # dial texture size: render_dial takes ~3 ms at 200 px, ~9 ms at 300


class Camera:
    def __init__(self, world: World, width: int = 640, height: int = 480,
                 hfov_deg: float = 70.0, jpeg_quality: int = 80,
                 max_range_m: float = 45.0) -> None:
        self.world = world
        self.w, self.h = width, height
        self.f = (width / 2) / math.tan(math.radians(hfov_deg) / 2)
        self.cx, self.cy = width / 2, height / 2
        self.quality = jpeg_quality
        self.max_range_m = max_range_m
        self.frame_id = 0
        self.target_gauge: str | None = None  # the pan-tilt head aims at this gauge
        self.ncol = width // COL_STEP
        px = (np.arange(self.ncol) + 0.5) * COL_STEP
        self.rel = np.arctan((self.cx - px) / self.f).astype(np.float32)  # + is left
        self.cos_rel = np.cos(self.rel)
        rows = np.arange(height, dtype=np.float32)
        k = np.clip((self.cy - rows) / self.cy, 0, 1)[:, None]
        sky = SKY_HORIZON * (1 - k) + SKY_TOP * k
        self.sky = np.repeat(sky[:, None, :], self.ncol, axis=1).astype(np.uint8)
        # floor: per row below the horizon, the distance along the optical axis
        frow = np.arange(int(self.cy) + 1, height, dtype=np.float32) + 0.5
        self.floor_rows = frow.astype(np.int32)
        self.floor_depth = (self.f * CAM_HEIGHT_M / (frow - self.cy))[:, None]  # (R, 1)
        self.floor_d = (self.floor_depth / self.cos_rel[None, :]).astype(np.float32)
        # fog quantised in 64 levels; palette[kind, level] with kind = road*2 + checker
        nfog = 64
        fog = np.exp(-np.minimum(self.floor_d, 200) / FOG_M)
        self.floor_fog_idx = np.clip((fog * (nfog - 1)).round(), 0, nfog - 1).astype(np.intp)
        kinds = np.array([GRAVEL, GRAVEL * 0.9, ROAD, ROAD * 0.9], np.float32)
        levels = np.linspace(0, 1, nfog, dtype=np.float32)[None, :, None]
        self.floor_palette = (kinds[:, None, :] * levels + SKY_HORIZON * (1 - levels)
                              ).astype(np.uint8)
        self.road_mask, self.road_res = self._road_raster()
        self._dial_cache: dict[tuple[str, int], np.ndarray] = {}
        self._ptz = None  # sim_robot.ptz.PtzView, made on first use
        self.last_ms = 0.0

    def _road_raster(self, res: float = 0.25) -> tuple[np.ndarray, float]:
        sx, sy = self.world.size_m
        m = np.zeros((int(sy / res), int(sx / res)), bool)
        for r in self.world.spec.get("roads", []):
            m[int(r["ymin"] / res):int(r["ymax"] / res),
              int(r["xmin"] / res):int(r["xmax"] / res)] = True
        return m, res

    # ------------------------------------------------------------------ rendering

    def set_target(self, gauge_id: str | None) -> None:
        """Aim the pan-tilt head at a gauge (None: look ahead again).
        Raises ValueError for a gauge the station does not have."""
        if gauge_id is not None and all(g.id != gauge_id for g in self.world.gauges):
            raise ValueError(f"no gauge {gauge_id!r} in this station")
        self.target_gauge = gauge_id

    def render(self, x: float, y: float, theta: float, t_s: float = 0.0) -> np.ndarray:
        """A BGR uint8 image of what the camera at (x, y, theta) sees: the scene ahead, or
        the zoomed view of the target gauge while the pan-tilt head is aimed at one."""
        target = self.target_gauge
        if target is not None:
            g = next((g for g in self.world.gauges if g.id == target), None)
            if g is not None:
                return self._ptz_view().render(g, x, y, theta, t_s)
        w = self.world
        ang = theta + self.rel
        rn, mn, rt, mt = w.raycast_layers(x, y, ang, self.max_range_m, tall_m=1.5, step_m=0.1)
        img = self.sky.copy()
        self._floor(img, x, y, ang)
        for r, m in ((rt, mt), (rn, mn)):
            dp = r * self.cos_rel
            ok = np.isfinite(dp)
            dp = np.where(ok, dp, 1e9)
            height = w.material_height[m]
            top = self.cy - self.f * (height - CAM_HEIGHT_M) / dp
            bot = self.cy + self.f * CAM_HEIGHT_M / dp
            col = w.material_bgr[m]
            # darken edges where the range jumps, fog with distance
            rf = np.where(ok, r, 1e3)
            jump = np.abs(np.diff(rf, prepend=rf[:1])) > 0.6
            shade = np.where(jump, 0.55, 1.0) * (0.8 + 0.2 * np.cos(ang * 3.0))
            fog = np.exp(-np.where(ok, r, 1e9) / FOG_M)[:, None]
            col = col * shade[:, None] * fog + SKY_HORIZON * (1 - fog)
            mask = ok & (r < rt + 0.01) if m is mn else ok
            t0 = np.clip(np.ceil(top), 0, self.h).astype(np.int32)
            t1 = np.clip(np.ceil(bot), 0, self.h).astype(np.int32)
            c8 = col.astype(np.uint8)
            for i in np.flatnonzero(mask & (t1 > t0)).tolist():
                img[t0[i]:t1[i], i] = c8[i]
        out = cv2.resize(img, (self.w, self.h), interpolation=cv2.INTER_NEAREST)
        self._gauges(out, x, y, theta, rn, t_s)
        return out

    def _ptz_view(self):
        if self._ptz is None:
            from .ptz import PtzView

            self._ptz = PtzView(self.world, self.w, self.h)
        return self._ptz

    def _floor(self, img: np.ndarray, x: float, y: float, ang: np.ndarray) -> None:
        d = self.floor_d  # range along each column ray, (rows, cols)
        fx = x + d * np.cos(ang).astype(np.float32)[None, :]
        fy = y + d * np.sin(ang).astype(np.float32)[None, :]
        rm, res = self.road_mask, self.road_res
        ci = np.clip((fx * (1 / res)).astype(np.int32), 0, rm.shape[1] - 1)
        ri = np.clip((fy * (1 / res)).astype(np.int32), 0, rm.shape[0] - 1)
        # palette index: road/gravel x checker light/dark, then fogged by distance row
        idx = rm[ri, ci].astype(np.uint8) * 2 + (
            (fx.astype(np.int32) + fy.astype(np.int32)) & 1).astype(np.uint8)
        pal = self.floor_palette[idx, self.floor_fog_idx]
        img[self.floor_rows] = pal

    def _gauges(self, img: np.ndarray, x: float, y: float, theta: float,
                near_range: np.ndarray, t_s: float) -> None:
        half_fov = math.atan(self.cx / self.f)
        for g in self.world.gauges:
            dx, dy = g.x - x, g.y - y
            dist = math.hypot(dx, dy)
            if not 0.4 < dist < 15.0:
                continue
            bearing = math.atan2(dy, dx)
            rel = (bearing - theta + math.pi) % (2 * math.pi) - math.pi
            if abs(rel) > half_fov:
                continue
            facing = math.cos(g.facing_rad - (bearing + math.pi))  # dial towards the camera?
            if facing < 0.2:
                continue
            u = self.cx - self.f * math.tan(rel)
            col = int(min(self.ncol - 1, max(0, u // COL_STEP)))
            if near_range[col] < dist - 0.3:
                continue  # something stands in front of it
            dp = dist * math.cos(rel)
            size = int(self.f * g.size_m / dp)
            if size < 8:
                continue
            v = self.cy - self.f * (g.height_m - CAM_HEIGHT_M) / dp
            dial = self._dial(g, g.value(t_s))
            wpx = max(4, int(size * facing))
            self._paste(img, cv2.resize(dial, (wpx, size), interpolation=cv2.INTER_AREA),
                        int(u - wpx / 2), int(v - size / 2))

    def _dial(self, g: Gauge, value: float) -> np.ndarray:
        q = int(round((value - g.min) / (g.max - g.min) * 400))
        key = (g.id, q)
        img = self._dial_cache.get(key)
        if img is None:
            qv = g.min + q / 400 * (g.max - g.min)
            img = _render_stock_dial(g, qv)
            if img is None:
                img = draw_simple_dial(g.min, g.max, qv, g.unit)
            if len(self._dial_cache) > 2000:
                self._dial_cache.clear()
            self._dial_cache[key] = img
        return img

    @staticmethod
    def _paste(img: np.ndarray, patch: np.ndarray, x0: int, y0: int) -> None:
        h, w = patch.shape[:2]
        H, W = img.shape[:2]
        xa, ya, xb, yb = max(0, x0), max(0, y0), min(W, x0 + w), min(H, y0 + h)
        if xa >= xb or ya >= yb:
            return
        sub = patch[ya - y0:yb - y0, xa - x0:xb - x0]
        yy, xx = np.ogrid[ya - y0:yb - y0, xa - x0:xb - x0]
        inside = ((xx - w / 2 + 0.5) / (w / 2)) ** 2 + ((yy - h / 2 + 0.5) / (h / 2)) ** 2 <= 1
        region = img[ya:yb, xa:xb]
        region[inside] = sub[inside]

    # ------------------------------------------------------------------ frames

    def capture_jpeg(self, x: float, y: float, theta: float, t_s: float = 0.0
                     ) -> tuple[int, bytes]:
        """(frame id, JPEG bytes); ``last_ms`` holds the render + encode time."""
        t0 = time.perf_counter()
        img = self.render(x, y, theta, t_s)
        ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, self.quality])
        if not ok:
            raise RuntimeError("JPEG encoding failed")
        self.frame_id = (self.frame_id + 1) & 0xFFFFFFFF
        self.last_ms = (time.perf_counter() - t0) * 1000
        return self.frame_id, buf.tobytes()


def _render_stock_dial(g: Gauge, value: float) -> np.ndarray | None:
    """Use the shared gauge renderer when present and it knows this gauge type."""
    if _gauge_render is None:
        return None
    try:
        spec = _gauge_render.stock_spec(g.type)
    except (KeyError, AttributeError):
        return None
    try:
        img = np.asarray(_gauge_render.render_dial(spec, value, size=DIAL_PX))
        if img.ndim == 2:
            img = cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)
        return np.ascontiguousarray(img[:, :, :3], dtype=np.uint8)
    except Exception as e:  # noqa: BLE001 - another module's renderer must not stop the camera
        log.warning("gauge_render failed for %s: %s; using the built-in dial", g.type, e)
        return None


def draw_simple_dial(vmin: float, vmax: float, value: float, unit: str,
                     size: int = 200) -> np.ndarray:
    """A plain pointer gauge: 270 degree scale, ticks, a black needle."""
    img = np.full((size, size, 3), 60, np.uint8)
    c = size // 2
    r = int(size * 0.46)
    cv2.circle(img, (c, c), r, (245, 245, 245), -1, cv2.LINE_AA)
    cv2.circle(img, (c, c), r, (30, 30, 30), max(2, size // 50), cv2.LINE_AA)
    start, sweep = math.radians(225), math.radians(270)  # min lower-left, clockwise

    def pt(frac: float, rr: float) -> tuple[int, int]:
        a = start - sweep * frac
        return int(c + rr * math.cos(a)), int(c - rr * math.sin(a))

    for i in range(41):
        frac = i / 40
        inner = 0.78 if i % 5 == 0 else 0.86
        cv2.line(img, pt(frac, r * inner), pt(frac, r * 0.95), (20, 20, 20),
                 2 if i % 5 == 0 else 1, cv2.LINE_AA)
    for i in range(9):
        frac = i / 8
        lab = f"{vmin + frac * (vmax - vmin):g}"
        p = pt(frac, r * 0.62)
        cv2.putText(img, lab, (p[0] - 4 * len(lab), p[1] + 4), cv2.FONT_HERSHEY_SIMPLEX,
                    size / 600, (20, 20, 20), 1, cv2.LINE_AA)
    cv2.putText(img, unit, (c - 10 * len(unit) // 2, int(c + r * 0.5)),
                cv2.FONT_HERSHEY_SIMPLEX, size / 450, (20, 20, 20), 1, cv2.LINE_AA)
    frac = min(1.0, max(0.0, (value - vmin) / (vmax - vmin)))
    cv2.line(img, pt(frac, -r * 0.15), pt(frac, r * 0.85), (10, 10, 10), max(2, size // 60),
             cv2.LINE_AA)
    cv2.circle(img, (c, c), max(3, size // 25), (10, 10, 10), -1, cv2.LINE_AA)
    return img
