"""The ``atlas`` gauge family: its random styles, its own drawing elements and backdrops.

Qt-free: numpy + OpenCV only.  Angles are degrees clockwise from 12 o'clock on the upright
dial, as in :mod:`sim_robot.gauge_styles`.  ``atlas`` is the held-out family of the meter
bench: none of its elements is drawn by a tuning family.  It leans on what real plant
gauges have and the other families under-represent:

* scales of 300-340 deg and of 90-180 deg (often turned off the vertical), a third of them
  counter-clockwise, a stop pin close below the minimum with the needle resting on it in
  about a third of the images;
* two-ended needles only: a ``dart`` (hairline tip, a delta fin on a long tail), a
  ``crescent`` (a half-moon counterweight) and a ``paddle`` (an oval counterweight), in
  cobalt, anthracite or lime; a hexagonal ``nut`` hub in zinc;
* a red ``flag`` set-point pointer (a hairline with a triangular flag) beside the needle;
* ``powder``-coated faces (speckled, lit unevenly from above) in bone, sage or sky-grey,
  and ``carbon`` weave faces; numerals in a ``block`` font (filled 3 x 5 cells), upright
  or turned along the radius;
* ``tee`` major ticks (a stroke with a cap at its outer end), ``spike`` minor ticks
  (tapering outward), a ``segmented`` arc (broken at every major tick), colour zones as
  ``rim`` sectors in teal, amber and carmine outside the ticks;
* print that looks like ticks: a ``fan`` logo (a little comb of radial strokes), a maker's
  ``plate`` with a bar code, maker text, unit text;
* ``bayonet`` bezels (a ring with three pressed lugs) in satin steel, blued steel or black
  oxide;
* its own backdrops: ``rack`` (an instrument rack: tubing, valves, tags, other atlas
  gauges) and ``grating`` (steel grating and beams).

:func:`atlas_params` returns the style fields; the drawing helpers are called by
:mod:`sim_robot.gauge_dial` and :mod:`sim_robot.gauge_scene` for these element kinds.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .gauge_draw import SC as _SC
from .gauge_draw import SH as _SH
from .gauge_draw import direction as _dir
from .gauge_draw import p as _p

__all__ = ["ATLAS", "ATLAS_NEEDLES", "ATLAS_NORMAL", "BLOCK_FONT", "atlas_params"]

ATLAS = "atlas"
BLOCK_FONT = -3  # numerals of filled 3 x 5 cells (:func:`block_text`)
ATLAS_NEEDLES = ("dart", "crescent", "paddle")
ATLAS_NORMAL = (150, 160, 20)  # teal: the normal zone
_AMBER, _CARMINE = (0, 150, 250), (70, 20, 180)
SETPOINT_RED = (18, 12, 226)

_POWDER = ((208, 222, 226), (190, 212, 196), (226, 214, 200))  # bone, sage, sky-grey
_POWDER_INK = (62, 44, 28)
_POWDER_NEEDLES = ((150, 60, 10), (52, 48, 44))  # cobalt, anthracite
_CARBON = (38, 35, 33)
_CARBON_INK = (214, 226, 232)
_CARBON_NEEDLES = ((40, 230, 170),)  # lime
_BEZELS = ((170, 165, 158), (120, 88, 58), (52, 47, 43))  # satin, blued, black oxide
_HUB = (182, 176, 168)  # zinc
_BRANDS = ("MERIDIAN", "VEKTOR", "KRONWELL")
_RANGES = ((0.0, 6.0, "bar", 1.0, 5), (0.0, 40.0, "bar", 5.0, 5), (0.0, 1000.0, "kPa", 100.0, 5),
           (-1.0, 0.0, "bar", 0.1, 5), (0.0, 100.0, "psi", 10.0, 5), (0.0, 0.6, "MPa", 0.1, 5),
           (0.0, 250.0, "bar", 50.0, 5), (0.0, 16.0, "bar", 2.0, 4))


def _pick(rng: np.random.Generator, seq):
    return seq[int(rng.integers(0, len(seq)))]


def atlas_params(rng: np.random.Generator, d: dict, value_range_fixed: bool) -> dict:
    """The atlas-specific fields of a style whose common fields are ``d``."""
    out: dict = {}
    if not value_range_fixed and rng.random() < 0.5:
        lo, hi, unit, step, minors = _pick(rng, _RANGES)
        out.update(min_value=lo, max_value=hi, unit=unit, major_step=step,
                   minor_per_major=minors, name=f"atlas_{lo:g}_{hi:g}{unit}")
    u = rng.random()  # wide (>= 300 deg), narrow (90-180 deg) or in between
    span = (float(rng.uniform(300, 340)) if u < 0.35 else
            float(rng.uniform(90, 180)) if u < 0.7 else float(rng.uniform(200, 290)))
    centre = float(rng.uniform(-45, 45)) if span <= 180 and rng.random() < 0.5 else 0.0
    a0, a1 = centre - span / 2, centre + span / 2
    if rng.random() < 0.3:  # counter-clockwise: values rise anticlockwise
        a0, a1 = a1, a0
    carbon = rng.random() < 0.35
    needle = _pick(rng, _CARBON_NEEDLES if carbon else _POWDER_NEEDLES)
    lo_v = out.get("min_value", d["min_value"])
    hi_v = out.get("max_value", d["max_value"])
    fs = hi_v - lo_v
    zones: tuple = ()
    if rng.random() < 0.4:
        a, b = sorted(rng.uniform(0.15, 0.85, 2))
        b = max(b, a + 0.2)
        zones = ((lo_v + a * fs, lo_v + min(b, 0.9) * fs, ATLAS_NORMAL),
                 (lo_v + min(b, 0.9) * fs, lo_v + min(b + 0.05, 0.95) * fs, _AMBER),
                 (lo_v + min(b + 0.05, 0.95) * fs, hi_v, _CARMINE))
    step = out.get("major_step", d["major_step"])
    n_major = round(fs / step)
    # numerals far enough apart along their circle not to touch (block glyphs 4 cells a char)
    chars = max(len(f"{v:.2f}".rstrip("0").rstrip(".")) for v in (lo_v, hi_v, lo_v + step))
    width = (4 * chars - 1) / 5 * d["text_h"]
    rn = 0.36 - d["tick_len"] - 0.03 - 0.5 * width
    every = next(k for k in (1, 2, 4, 5, 10, n_major)
                 if math.radians(span / n_major * k) * rn >= 1.2 * width or k == n_major)
    out.update({
        "label_every": every, "min_angle_deg": a0, "max_angle_deg": a1,
        "face_kind": "carbon" if carbon else "powder",
        "face_bgr": _CARBON if carbon else _pick(rng, _POWDER),
        "ink_bgr": _CARBON_INK if carbon else _POWDER_INK,
        "font": BLOCK_FONT, "italic": False, "numerals": "inside",
        "numeral_orient": "radial" if rng.random() < 0.4 else "upright",
        "scale_radius": float(rng.uniform(0.36, 0.39)), "arc": "segmented",
        "major_kind": "tee", "minor_kind": "spike", "bezel_kind": "bayonet",
        "bezel_bgr": _pick(rng, _BEZELS), "needle_shape": _pick(rng, ATLAS_NEEDLES),
        "needle_bgr": needle, "needle_width": float(rng.uniform(0.014, 0.024)),
        "tail_len": float(rng.uniform(0.11, 0.17)), "hub_kind": "nut", "hub_bgr": _HUB,
        "logo": "fan", "brand": _pick(rng, _BRANDS) if rng.random() < 0.7 else "",
        "face_print": "plate" if rng.random() < 0.6 else "none",
        "zone_kind": "rim", "zones": zones, "face_radius": 0.44,
        "needle_len": float(rng.uniform(0.32, 0.37)), "stop_pin": bool(rng.random() < 0.75),
        "pin_offset_deg": float(rng.uniform(4.5, 8.0)), "setpoint_kind": "flag",
        "setpoint": (float(lo_v + rng.uniform(0.1, 0.9) * fs) if rng.random() < 0.3
                     else None)})
    return out


# ----------------------------------------------------------------------------- drawing


def _poly(img, c, ang, pts, colour) -> None:
    """Fill ``pts`` given in (along the ray at ``ang``, across it) about the point ``c``."""
    dx, dy = _dir(ang)
    nx, ny = -dy, dx
    q = np.array([_p(c[0] + dx * s + nx * t, c[1] + dy * s + ny * t) for s, t in pts], np.int32)
    cv2.fillPoly(img, [q], colour, cv2.LINE_AA, _SH)


def face_layer(kind: str, layer: np.ndarray, dx: np.ndarray, dy: np.ndarray,
               rr: np.ndarray, face_radius: float, trng: np.random.Generator) -> np.ndarray:
    """Powder coat (a fine speckle, lit from above) or a carbon twill weave."""
    size = layer.shape[0]
    if kind == "powder":
        speck = cv2.GaussianBlur(trng.normal(0, 9, (size, size)).astype(np.float32), (0, 0), 0.7)
        lit = (1.06 - 0.14 * (dy / size + 0.5)).astype(np.float32)  # brighter at the top
        return layer * lit[..., None] + speck[..., None]
    p = max(3.0, size / 60.0)  # carbon: 2/2 twill, bundles shaded across their width
    u, v = (dx + dy) / p, (dx - dy) / p
    cell = (np.floor(u) + np.floor(v)) % 2
    shade = np.where(cell > 0, np.sin(np.pi * (u % 1)), np.sin(np.pi * (v % 1)))
    return layer + (14.0 * shade - 5.0).astype(np.float32)[..., None]


def bezel_layer(col: np.ndarray, dx: np.ndarray, dy: np.ndarray, rr: np.ndarray,
                size: int) -> np.ndarray:
    """A turned ring lit from the top, with three pressed lugs at 30, 150 and 270 deg."""
    ang = np.degrees(np.arctan2(dx, -dy))
    lit = (0.8 + 0.3 * (-dy / (0.5 * size))).clip(0.5, 1.2)
    groove = 1.0 - 0.35 * np.exp(-(((rr - 0.465) / 0.004) ** 2))
    lug = np.zeros_like(rr)
    for a in (30.0, 150.0, 270.0):
        lug = np.maximum(lug, (np.abs((ang - a + 180) % 360 - 180) < 7).astype(np.float32))
    shade = lit * groove * (1 - 0.35 * lug * (rr > 0.455))
    return col[None, None, :] * shade[..., None]


def draw_tick(img, c: float, ang: float, shape: str, a_in: float, a_out: float, w: float,
              colour) -> None:
    """A ``tee`` (a stroke with a cap across its outer end) or a ``spike`` (a thin
    triangle, wide at the inner end, pointed at the outer)."""
    if shape == "tee":
        half = max(0.6, w / 2)
        cap = max(1.0, 0.5 * w)
        _poly(img, (c, c), ang, [(a_in, -half), (a_out - cap, -half), (a_out - cap, -2.2 * w),
                                 (a_out, -2.2 * w), (a_out, 2.2 * w), (a_out - cap, 2.2 * w),
                                 (a_out - cap, half), (a_in, half)], colour)
    else:  # spike
        _poly(img, (c, c), ang, [(a_in, -max(0.7, 0.8 * w)), (a_out, 0.0),
                                 (a_in, max(0.7, 0.8 * w))], colour)


def segmented_arc(img, c: float, r: float, majors: list[float], lw: float, colour) -> None:
    """The scale's arc at ``r``, broken round every major tick (gaps of 2.5 deg)."""
    gap = 2.5
    for a0, a1 in zip(majors[:-1], majors[1:], strict=True):
        lo, hi = sorted((a0, a1))
        if hi - lo <= 2 * gap:
            continue
        cv2.ellipse(img, _p(c, c), (int(r * _SC), int(r * _SC)), 0, lo + gap - 90,
                    hi - gap - 90, colour, max(1, int(round(lw))), cv2.LINE_AA, _SH)


def rim_zones(img, c: float, r0: float, r1: float, zones, angle_of) -> None:
    """Colour zones as filled annular sectors between radii ``r0`` and ``r1``."""
    for v0, v1, col in zones:
        lo, hi = sorted((angle_of(v0), angle_of(v1)))
        qs = np.linspace(lo, hi, max(2, int(hi - lo) + 2))
        pts = [(c + _dir(q)[0] * r1, c + _dir(q)[1] * r1) for q in qs]
        pts += [(c + _dir(q)[0] * r0, c + _dir(q)[1] * r0) for q in qs[::-1]]
        cv2.fillPoly(img, [np.array([_p(*p) for p in pts], np.int32)], col, cv2.LINE_AA, _SH)


# block glyphs: 3 columns x 5 rows, one string of three bits per row (top first)
_BLOCKS = {"0": "111101101101111", "1": "010110010010111", "2": "111001111100111",
           "3": "111001011001111", "4": "101101111001001", "5": "111100111001111",
           "6": "111100111101111", "7": "111001010010010", "8": "111101111101111",
           "9": "111101111001111", "-": "000000111000000", ".": "000000000000010",
           "A": "010101111101101", "B": "110101110101110", "C": "011100100100011",
           "D": "110101101101110", "E": "111100110100111", "F": "111100110100100",
           "G": "011100101101011", "H": "101101111101101", "I": "111010010010111",
           "K": "101101110101101", "L": "100100100100111", "M": "101111111101101",
           "N": "110101101101101", "O": "010101101101010", "P": "110101110100100",
           "R": "110101110101101", "S": "011100010001110", "T": "111010010010010",
           "U": "101101101101111", "V": "101101101101010", "W": "101101111111101"}
_BLOCK_FALLBACK = "111111111111111"
_ADVANCE = 4.0  # glyph pitch in cells (three cells and a space)


def block_width(txt: str, height_px: float) -> float:
    return (len(txt) * _ADVANCE - 1) * height_px / 5.0


def block_text(img, txt: str, x: float, y: float, height_px: float, colour,
               angle_deg: float = 0.0) -> None:
    """Block glyphs centred on ``(x, y)``, turned ``angle_deg`` clockwise (0: upright)."""
    cell = height_px / 5.0
    ca, sa = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    u0, v0 = -block_width(txt, height_px) / 2, -height_px / 2
    e = 0.04 * cell  # overlap, so neighbouring cells print as one solid stroke

    def to_img(u, v):
        return _p(x + u * ca - v * sa, y + u * sa + v * ca)

    for k, ch in enumerate(txt):
        bits = _BLOCKS.get(ch.upper(), "0" * 15 if ch == " " else _BLOCK_FALLBACK)
        for i, b in enumerate(bits):
            if b != "1":
                continue
            u = u0 + (k * _ADVANCE + i % 3) * cell
            v = v0 + (i // 3) * cell
            q = [to_img(u - e, v - e), to_img(u + cell + e, v - e),
                 to_img(u + cell + e, v + cell + e), to_img(u - e, v + cell + e)]
            cv2.fillPoly(img, [np.array(q, np.int32)], colour, cv2.LINE_AA, _SH)


def _wide(st) -> bool:
    return abs(st.max_angle_deg - st.min_angle_deg) > 300


def unit_y(st, size: int) -> float:
    """Where the unit is printed: higher on a wide scale, whose end numerals sit low."""
    return size / 2 + (0.155 if _wide(st) else 0.2) * size


def face_print(img, st, size: int) -> None:
    """The fan logo beside the maker's name, and the maker's plate (inverse text, a bar
    code) when the style has one: print that looks like ticks."""
    c = size / 2
    q = 0.03 * size  # the fan: five strokes round a point, left of the brand
    lx = c - (block_width(st.brand, 0.7 * st.text_h * size) / 2 + 1.6 * q if st.brand else 0)
    ly = c - 0.14 * size - 1.3 * q
    th = max(1, int(round(size / 220)))
    for k in range(5):
        dx, dy = _dir(-40 + 20 * k)
        cv2.line(img, _p(lx + dx * 0.35 * q, ly + q + dy * 0.35 * q),
                 _p(lx + dx * q * 1.2, ly + q + dy * q * 1.2), st.ink_bgr, th, cv2.LINE_AA, _SH)
    if st.face_print != "plate":
        return
    ph, py = 0.05 * size, c + (0.09 if _wide(st) else 0.1) * size
    pw = block_width("EN837 CL1.6", 0.55 * ph) + 0.3 * ph
    cv2.rectangle(img, _p(c - pw / 2, py - ph / 2), _p(c + pw / 2, py + ph / 2), st.ink_bgr, -1,
                  cv2.LINE_AA, _SH)
    block_text(img, "EN837 CL1.6", c, py, 0.55 * ph, st.face_bgr)
    if not _wide(st):  # the bottom of the face is free
        bx, by, bh = c - 0.07 * size, c + 0.27 * size, 0.035 * size
        rng = np.random.default_rng(st.texture_seed)
        x = bx
        while x < c + 0.07 * size:
            bw = float(rng.choice((0.6, 1.2, 1.8))) * size / 300
            cv2.rectangle(img, _p(x, by), _p(x + bw, by + bh), st.ink_bgr, -1, cv2.LINE_AA, _SH)
            x += bw + float(rng.choice((0.8, 1.6))) * size / 300


def needle_polys(shape: str, L: float, w: float, T: float) -> list[list[tuple[float, float]]]:
    """Two-ended needles in (along, across) coordinates: tip at (L, 0), pivot at the origin;
    every tail is wider than the hairline tip."""
    body = [(0, -0.9 * w), (0.5 * L, -0.5 * w), (L, -0.06 * w), (L, 0.06 * w), (0.5 * L, 0.5 * w),
            (0, 0.9 * w)]
    if shape == "dart":  # a long tail ending in a delta fin
        return [body + [(-0.5 * T, 0.5 * w), (-T, 3.0 * w), (-T, -3.0 * w), (-0.5 * T, -0.5 * w)]]
    tail = [(-T, 0.5 * w), (-T, -0.5 * w)]
    if shape == "crescent":  # a half-moon counterweight on the tail's end
        r = 3.0 * w
        cx = -0.7 * T
        outer = [(cx + r * math.cos(math.radians(a)), r * math.sin(math.radians(a)))
                 for a in np.linspace(90, 270, 13)]
        inner = [(cx - 0.3 * r + 0.65 * r * math.cos(math.radians(a)),
                  0.65 * r * math.sin(math.radians(a))) for a in np.linspace(270, 90, 13)]
        return [body + tail, outer + inner]
    oval = [(-0.65 * T + 0.35 * T * math.cos(t), 2.0 * w * math.sin(t))  # paddle
            for t in np.linspace(0, 2 * math.pi, 24, endpoint=False)]
    return [body + tail, oval]


def nut_hub(img, c: float, r: float, colour) -> None:
    """A hexagonal nut on the pivot with a dark screw head in it."""
    qs = [math.radians(60 * k + 30) for k in range(6)]
    pts = [(c + r * math.cos(q), c + r * math.sin(q)) for q in qs]
    cv2.fillPoly(img, [np.array([_p(*p) for p in pts], np.int32)], colour, cv2.LINE_AA, _SH)
    dark = tuple(int(0.45 * v) for v in colour)
    cv2.polylines(img, [np.array([_p(*p) for p in pts], np.int32)], True, dark, 1, cv2.LINE_AA,
                  _SH)
    cv2.circle(img, _p(c, c), int(0.35 * r * _SC), dark, -1, cv2.LINE_AA, _SH)


def flag_setpoint(img, c: float, ang: float, L: float, w: float, hub_r: float) -> None:
    """The red set-point pointer: a hairline with a triangular flag near its end and a
    ring on the pivot."""
    _poly(img, (c, c), ang, [(-0.12 * L, -0.35 * w), (0.97 * L, -0.25 * w),
                             (0.97 * L, 0.25 * w), (-0.12 * L, 0.35 * w)], SETPOINT_RED)
    _poly(img, (c, c), ang, [(0.8 * L, 0.0), (0.92 * L, 0.0), (0.86 * L, 3.0 * w)], SETPOINT_RED)
    cv2.circle(img, _p(c, c), int(1.5 * hub_r * _SC), SETPOINT_RED, max(1, int(round(w))),
               cv2.LINE_AA, _SH)


# ----------------------------------------------------------------------------- backdrops


def backdrop(rng: np.random.Generator, w: int, h: int, kind: str) -> np.ndarray:
    """``rack``: an instrument rack (a panel with tubing runs, valves, tags, cable ties);
    ``grating``: steel floor grating behind I-beams."""
    if kind == "grating":
        base = rng.uniform(60, 110)
        img = np.full((h, w, 3), base * 0.6, np.float32)
        pitch = int(rng.integers(14, 26))
        steel = (base * np.array([1.05, 1.0, 0.95])).tolist()
        for x in range(0, w, pitch):
            cv2.line(img, (x, 0), (x, h), steel, 3)
        for y in range(0, h, pitch * 3):
            cv2.line(img, (0, y), (w, y), steel, 2)
        for _ in range(int(rng.integers(1, 3))):  # beams, painted, with flanges
            col = rng.uniform(40, 200, 3)
            y0, t = int(rng.integers(0, h)), int(rng.integers(40, 90))
            cv2.rectangle(img, (0, y0), (w, y0 + t), (col * 0.8).tolist(), -1)
            cv2.rectangle(img, (0, y0), (w, y0 + 8), col.tolist(), -1)
            cv2.rectangle(img, (0, y0 + t - 8), (w, y0 + t), col.tolist(), -1)
    else:  # rack
        base = rng.uniform(110, 180, 3)
        img = np.empty((h, w, 3), np.float32)
        img[:] = base
        for _ in range(int(rng.integers(3, 7))):  # tubing: bent runs of bright tube
            pts = np.cumsum(rng.integers(-120, 121, (5, 2)), axis=0) + [w // 2, h // 2]
            cv2.polylines(img, [pts.astype(np.int32)], False, (175, 185, 195),
                          int(rng.integers(5, 11)), cv2.LINE_AA)
        for _ in range(int(rng.integers(2, 6))):  # valve bodies with round handles
            x, y = int(rng.integers(0, w)), int(rng.integers(0, h))
            cv2.rectangle(img, (x - 12, y - 9), (x + 12, y + 9), (120, 120, 125), -1)
            cv2.circle(img, (x, y - 22), int(rng.integers(10, 20)), (30, 120, 220), 4,
                       cv2.LINE_AA)
        for _ in range(int(rng.integers(2, 5))):  # yellow tags with text
            x, y = int(rng.integers(0, w - 70)), int(rng.integers(0, h - 30))
            cv2.rectangle(img, (x, y), (x + 64, y + 26), (40, 210, 235), -1)
            block_text(img, f"PT{int(rng.integers(100, 999))}", x + 32, y + 13, 12.0,
                       (20, 20, 20))
    img += rng.normal(0, 4, img.shape).astype(np.float32)
    return np.clip(img, 0, 255).astype(np.uint8)
