"""The ``foundry`` gauge family: its random styles and its own dial renderer.

Qt-free: numpy + OpenCV only.  Angles are degrees clockwise from 12 o'clock on the upright
dial, as in :mod:`sim_robot.gauge_styles`.  ``foundry`` is the held-out family of the meter
bench.  It shares no drawing code with the other families (only the fixed-point helpers of
:mod:`sim_robot.gauge_draw`) and aims at what photographs of real plant gauges show:

* printed paper faces, white yellowed a little with age, with paper grain, or bead-blasted
  ``satin`` aluminium; light falling unevenly across the face and the bezel's shadow on it;
* print in its own typeface (:mod:`sim_robot.gauge_foundry_type`): numerals, the maker's
  name and a ``crest``, the unit ("bar", "psi", "kgf/cm²", ...), EN 837 class marks, and on
  dual-scale dials an inner second scale with its own ticks and numerals in red;
* ``keystone`` major and ``sliver`` minor ticks (sectors of constant angular width), a
  ``hairline`` arc or an anti-parallax ``mirror`` band, colour zones ``inlay``-ed along the
  ticks' inner edge;
* needles: a ``lancet`` (blade with a teardrop counterweight), a two-ended ``lozenge`` and a
  single-ended ``spear``, with a ridge of light along them and a soft shadow on the face,
  on a shaded ``dome`` hub; a red ``drag`` mark pointer on the glass with its knob;
* ``polished`` chrome and ``crimped`` stainless bezels that reflect their surroundings;
* the glass: reflections of the room and of a window, and in glycerine-filled cases the
  meniscus of the fill at the top and an air bubble;
* scales of 270 deg, 240-300 deg and some of 90 deg, counter-clockwise vacuum gauges, and a
  stop pin against which the needle rests (physically: touching the pin) at the scale's
  zero end.

:func:`foundry_params` returns the style fields; :func:`draw_dial` draws a dial and returns
its ground truth exactly as :func:`sim_robot.gauge_dial.draw_dial` does for the others.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .gauge_draw import SC, SH, direction, p
from .gauge_foundry_glass import glass, needle_shadow
from .gauge_foundry_type import Ink, rule, text_width, typeset

__all__ = ["FOUNDRY", "FOUNDRY_FONT", "FOUNDRY_NEEDLES", "FOUNDRY_NORMAL", "draw_dial",
           "foundry_params", "needle_angle"]

FOUNDRY = "foundry"
FOUNDRY_FONT = -4  # the "grotesk" skeleton typeface (:mod:`.gauge_foundry_type`)
FOUNDRY_NEEDLES = ("lancet", "lozenge", "spear")
FOUNDRY_TWO_ENDED = ("lancet", "lozenge")
FOUNDRY_NORMAL = (72, 150, 40)  # the green of a normal-range inlay
FOUNDRY_RED = (28, 22, 188)  # red print, the red zone and the drag pointer
_INKS = ((26, 24, 22), (44, 28, 22))  # black, navy-black
_NEEDLES = ((16, 15, 14), (34, 30, 178))  # black, red
_BEZELS = {"polished": ((214, 216, 220), (190, 193, 198)), "crimped": ((168, 172, 176),)}
_HUBS = ((176, 178, 182), (36, 34, 34), (64, 120, 176))  # chrome, black, red brass
_BRANDS = ("HALDEN", "OKTAVA", "BRENNER", "TEMPRA", "ARMATEK")
_RANGES = (  # (min, max, unit, major step, minors per major): EN 837 ranges
    (0.0, 1.6, "bar", 0.2, 4), (0.0, 2.5, "bar", 0.5, 5), (0.0, 4.0, "bar", 0.5, 5),
    (0.0, 6.0, "bar", 1.0, 5), (0.0, 10.0, "bar", 1.0, 5), (0.0, 16.0, "bar", 2.0, 4),
    (0.0, 25.0, "bar", 5.0, 5), (0.0, 40.0, "bar", 5.0, 5), (0.0, 60.0, "bar", 10.0, 5),
    (0.0, 100.0, "psi", 10.0, 5), (0.0, 160.0, "psi", 20.0, 4), (0.0, 300.0, "psi", 50.0, 5),
    (0.0, 1.0, "MPa", 0.1, 5), (0.0, 2.5, "MPa", 0.5, 5), (0.0, 10.0, "kgf/cm2", 1.0, 5),
    (0.0, 20.0, "kgf/cm2", 2.0, 4), (0.0, 400.0, "kPa", 50.0, 5), (-1.0, 0.0, "bar", 0.1, 5),
    (-100.0, 0.0, "kPa", 10.0, 5), (-1.0, 1.5, "bar", 0.5, 5), (-1.0, 3.0, "bar", 0.5, 5))
_SECOND = {"bar": (14.5038, "psi"), "psi": (0.0689476, "bar"), "MPa": (145.038, "psi"),
           "kgf/cm2": (14.2233, "psi"), "kPa": (0.145038, "psi")}


def _pick(rng: np.random.Generator, seq):
    return seq[int(rng.integers(0, len(seq)))]


def _fmt(v: float) -> str:
    s = f"{v:.2f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def _printed(unit: str) -> str:
    return unit.replace("cm2", "cm\u00b2")


def foundry_params(rng: np.random.Generator, d: dict, value_range_fixed: bool) -> dict:
    """The foundry-specific fields of a style whose common fields are ``d``."""
    out: dict = {}
    if not value_range_fixed:
        lo, hi, unit, step, minors = _pick(rng, _RANGES)
        out.update(min_value=lo, max_value=hi, unit=unit, major_step=step,
                   minor_per_major=minors, name=f"foundry_{lo:g}_{hi:g}{unit}")
    lo, hi = out.get("min_value", d["min_value"]), out.get("max_value", d["max_value"])
    unit, step = out.get("unit", d["unit"]), out.get("major_step", d["major_step"])
    u = rng.random()
    span = (270.0 if u < 0.45 else float(rng.uniform(240, 300)) if u < 0.8
            else float(rng.uniform(88, 95)) if u < 0.93 else float(rng.uniform(300, 320)))
    centre = float(rng.uniform(-40, 40)) if span < 100 and rng.random() < 0.4 else 0.0
    vacuum = hi <= 0.0
    a0, a1 = centre - span / 2, centre + span / 2
    if vacuum or rng.random() < 0.15:  # values rise anticlockwise
        a0, a1 = a1, a0
    paper = rng.random() < 0.8
    face = ((int(rng.integers(214, 237)), int(rng.integers(232, 245)), int(rng.integers(240, 253)))
            if paper else tuple(int(v) + k for v, k in zip([rng.integers(186, 207)] * 3,
                                                           (0, 2, 3), strict=True)))
    second = _SECOND.get(unit) if rng.random() < 0.4 and span > 200 else None
    text_h = float(rng.uniform(0.042, 0.056)) * (0.88 if second else 1.0)
    tick_len = float(rng.uniform(0.045, 0.065))
    scale_r = float(rng.uniform(0.36, 0.385))
    n_major = max(1, round((hi - lo) / step))
    tw = max(text_width(_fmt(lo + k * step), text_h) for k in range(n_major + 1))
    half = 0.5 * math.hypot(tw, text_h) * 0.85
    rn = scale_r - tick_len - 0.02 - half
    # neighbouring labels' centres at least a text's width and half its height apart
    every = next(k for k in range(1, n_major + 1)  # both ends always labelled
                 if n_major % k == 0 and (2 * rn * math.sin(math.radians(span / n_major * k) / 2)
                                          >= tw + 0.5 * text_h or k == n_major))
    shape = _pick(rng, FOUNDRY_NEEDLES)
    setpoint = float(lo + rng.uniform(0.1, 0.9) * (hi - lo)) if rng.random() < 0.25 else None
    needle = _NEEDLES[0] if setpoint is not None or rng.random() < 0.75 else _NEEDLES[1]
    zones: tuple = ()
    if rng.random() < 0.25:
        a = float(rng.uniform(0.55, 0.8))
        zones = ((lo + (hi - lo) * a, hi, FOUNDRY_RED),)
        if rng.random() < 0.5:
            zones = ((lo + (hi - lo) * float(rng.uniform(0.1, 0.3)), lo + (hi - lo) * a,
                      FOUNDRY_NORMAL), *zones)
    bezel = "polished" if rng.random() < 0.6 else "crimped"
    brand = _pick(rng, _BRANDS) if rng.random() < 0.75 else ""
    out.update({
        "label_every": every, "min_angle_deg": a0, "max_angle_deg": a1,
        "face_kind": "paper" if paper else "satin", "face_bgr": face,
        "ink_bgr": _pick(rng, _INKS), "font": FOUNDRY_FONT, "italic": False,
        "numerals": "inside", "numeral_orient": "upright", "text_h": text_h,
        "text_weight": float(rng.uniform(0.11, 0.16)), "brand": brand,
        "logo": "crest" if brand and rng.random() < 0.5 else "none",
        "face_print": "class" if rng.random() < 0.7 else "none",
        "second_scale": second[0] if second else None, "second_unit": second[1] if second else "",
        "bezel_kind": bezel, "bezel_bgr": _pick(rng, _BEZELS[bezel]),
        "scale_radius": scale_r, "tick_len": tick_len,
        "tick_width": float(rng.uniform(0.006, 0.011)), "major_kind": "keystone",
        "minor_kind": "sliver", "arc": "mirror" if rng.random() < 0.3 else "hairline",
        "zones": zones, "zone_kind": "inlay", "face_radius": float(rng.uniform(0.415, 0.435)),
        "needle_shape": shape, "needle_bgr": needle,
        "needle_len": scale_r - float(rng.uniform(0.008, 0.028)),
        "needle_width": float(rng.uniform(0.012, 0.02)),
        "tail_len": {"lancet": float(rng.uniform(0.07, 0.11)),
                     "lozenge": float(rng.uniform(0.09, 0.14)), "spear": 0.03}[shape],
        "hub_radius": float(rng.uniform(0.025, 0.042)), "hub_kind": "dome",
        "hub_bgr": _pick(rng, _HUBS), "setpoint": setpoint, "setpoint_kind": "drag",
        "stop_pin": bool(rng.random() < 0.7), "pin_offset_deg": float(rng.uniform(5.0, 9.0)),
        "rest_at_max": vacuum, "fill": "glycerine" if rng.random() < 0.35 else "dry"})
    return out


# ----------------------------------------------------------------------------- geometry


def _pin(st, size: int) -> tuple[float, float, float]:
    """The stop pin: (dial angle, radius px, pin radius px)."""
    return st.pin_angle_deg, 0.7 * st.needle_len * size, 0.009 * size


def needle_angle(st, value: float, size: int = 300) -> float:
    """Where the needle is drawn: at the value, or against the stop pin at the rest end
    (its side touching the pin: turned from the pin's angle by the pin's radius plus the
    needle's half-width there, seen from the pivot)."""
    lo, hi = st.min_value, st.max_value
    at_rest = st.stop_pin and (value >= hi if st.rest_at_max else value <= lo)
    if not at_rest:
        return st.angle_of(min(max(value, lo), hi))
    ang, rp, pr = _pin(st, size)
    half = 0.55 * st.needle_width * size / 2 * 1.4
    toward_scale = -st.direction if st.rest_at_max else st.direction
    return ang + toward_scale * math.degrees(math.asin(min(0.5, (pr + half) / rp)))


# ----------------------------------------------------------------------------- drawing


def _disc_alpha(size: int, c: float, r: float) -> np.ndarray:
    m = np.zeros((size, size), np.uint8)
    cv2.circle(m, p(c, c), int(r * SC), 255, -1, cv2.LINE_AA, SH)
    return m.astype(np.float32)[..., None] / 255.0


def _case(st, size: int, rng: np.random.Generator) -> np.ndarray:
    """What lies round the face: a soft photographic backdrop in the crop's corners and
    the bezel ring, which mirrors the room (bright above, dark below, window streaks)."""
    c = size / 2.0
    yy, xx = np.mgrid[0:size, 0:size].astype(np.float32)
    dx, dy = xx - c, yy - c
    rr = np.hypot(dx, dy) / size
    tint = rng.uniform(0.85, 1.1, 3).astype(np.float32)  # a room in soft focus behind
    back = cv2.resize(rng.uniform(70, 190, (3, 3, 1)).astype(np.float32), (size, size),
                      interpolation=cv2.INTER_CUBIC)[..., None] * tint
    ang = np.arctan2(dx, -dy)
    env = np.zeros_like(rr)
    for k in (1, 2, 3, 5):  # the room as seen in the metal: a smooth random band of light
        env += rng.uniform(0.1, 0.5) / k * np.cos(k * ang + rng.uniform(0, 2 * np.pi))
    env += 0.35 * (-dy / c)  # the sky or the ceiling lights above, the floor below
    for _ in range(int(rng.integers(1, 4))):  # windows: narrow bright reflections
        a0 = rng.uniform(-np.pi, np.pi)
        off = (ang - a0 + np.pi) % (2 * np.pi) - np.pi
        env += 1.2 * np.exp(-(off / rng.uniform(0.03, 0.09)) ** 2)
    r0, r1 = st.face_radius, 0.49
    t = np.clip((rr - r0) / (r1 - r0), 0, 1)  # across the ring: a rounded profile
    crest = np.clip(np.sin(np.pi * t), 0, 1) ** 0.6
    col = np.array(st.bezel_bgr, np.float32)
    if st.bezel_kind == "crimped":  # a flat lip, pressed in small dents round its edge
        dents = 0.5 + 0.5 * np.cos(ang * float(rng.integers(36, 60)))
        shade = 0.62 + 0.18 * env * crest + 0.2 * crest - 0.25 * dents * (t > 0.72)
    else:
        shade = 0.45 + 0.45 * env * crest + 0.25 * crest ** 3
    ring = col[None, None, :] * np.clip(shade, 0.15, 1.5)[..., None]
    ring += 40.0 * np.clip(env - 0.8, 0, None)[..., None] * crest[..., None]  # specular
    a = _disc_alpha(size, c, r1 * size)
    return np.clip(back * (1 - a) + ring * a, 0, 255)


def _face(st, size: int, rng: np.random.Generator, light: tuple[float, float]) -> np.ndarray:
    """The face: paper (grain, yellowing, darker toward the edge) or bead-blasted
    aluminium, lit from one side, with the bezel's shadow near the rim away from the light."""
    c = size / 2.0
    yy, xx = np.mgrid[0:size, 0:size].astype(np.float32)
    col = np.array(st.face_bgr, np.float32)
    lx, ly = light
    grad = 1.0 + 0.07 * ((xx - c) * lx + (yy - c) * ly) / c
    if st.face_kind == "paper":
        fibres = cv2.GaussianBlur(rng.normal(0, 1, (size, size)).astype(np.float32), (0, 0), 1.8,
                                  sigmaY=0.5)
        grain = 3.0 * fibres + cv2.GaussianBlur(rng.normal(0, 2, (size, size)).astype(
            np.float32), (0, 0), 0.6)
        age = cv2.resize(rng.uniform(0, 1, (5, 5)).astype(np.float32), (size, size),
                         interpolation=cv2.INTER_CUBIC).clip(0, 1) * rng.uniform(0.02, 0.07)
        layer = col[None, None, :] * grad[..., None] + grain[..., None]
        layer *= 1 - age[..., None] * np.array([1.6, 0.6, 0.2], np.float32)  # yellowing
    else:
        grain = cv2.GaussianBlur(rng.normal(0, 5, (size, size)).astype(np.float32), (0, 0), 0.7)
        sheen = 10.0 * np.exp(-(((xx - yy) / size - rng.uniform(-0.3, 0.3)) / 0.25) ** 2)
        layer = col[None, None, :] * grad[..., None] + (grain + sheen)[..., None]
    rr = np.hypot(xx - c, yy - c) / (st.face_radius * size)
    layer *= (1 - 0.06 * rr ** 4)[..., None]
    off = rng.uniform(0.008, 0.025) * size  # the bezel's shadow, cast away from the light
    rs = np.hypot(xx - c + lx * off, yy - c + ly * off) / (st.face_radius * size)
    layer *= (1 - rng.uniform(0.2, 0.4) * np.clip((rs - 0.97) / 0.05, 0, 1))[..., None]
    return layer


def _ticks(st, size: int, ink: Ink, red: Ink, face: np.ndarray) -> None:
    c = size / 2.0
    r_in, r_out = (v * size for v in st.tick_span())
    for v0, v1, col in st.zones:  # inlays along the ticks' inner edge
        z = red if col == FOUNDRY_RED else Ink(size, col)
        z.circle_arc((c, c), r_in + 0.18 * (r_out - r_in), st.angle_of(v0), st.angle_of(v1),
                     0.36 * (r_out - r_in))
        if z is not red:
            z.lay(face, 0.9)
    if st.arc == "mirror":  # a silvered band outside the ticks, with a bright streak
        band = Ink(size, (236, 238, 240))
        band.circle_arc((c, c), r_out + 0.012 * size, st.min_angle_deg, st.max_angle_deg,
                        0.016 * size)
        band.lay(face, 0.85, 0)
        dark = Ink(size, (120, 122, 126))
        dark.circle_arc((c, c), r_out + 0.0205 * size, st.min_angle_deg, st.max_angle_deg,
                        0.0015 * size)
        dark.lay(face, 0.8, 0)
    else:
        ink.circle_arc((c, c), r_out, st.min_angle_deg, st.max_angle_deg,
                       max(0.7, 0.45 * st.tick_width * size))
    w = st.tick_width * size
    for _v, ang, kind in st.tick_list():
        frac, wo, wi = {"major": (1.0, w, 0.55 * w), "medium": (0.72, 0.6 * w, 0.4 * w),
                        "minor": (0.5, 0.42 * w, 0.3 * w)}[kind]
        a_in = r_out - (r_out - r_in) * frac
        ux, uy = direction(ang)
        nx, ny = -uy, ux
        ink.poly([(c + ux * r_out + nx * wo / 2, c + uy * r_out + ny * wo / 2),
                  (c + ux * a_in + nx * wi / 2, c + uy * a_in + ny * wi / 2),
                  (c + ux * a_in - nx * wi / 2, c + uy * a_in - ny * wi / 2),
                  (c + ux * r_out - nx * wo / 2, c + uy * r_out - ny * wo / 2)])


def _second_scale(st, size: int, r2: float, red: Ink) -> None:
    """The inner scale in the second unit: an arc, ticks pointing inward, small numerals."""
    c = size / 2.0
    k = st.second_scale
    lo, hi = st.min_value * k, st.max_value * k
    raw = (hi - lo) / 6
    e = 10 ** math.floor(math.log10(raw))
    step = next(m * e for m in (1, 2, 2.5, 5, 10) if m * e >= raw)
    red.circle_arc((c, c), r2, st.min_angle_deg, st.max_angle_deg, 0.7)
    h = 0.62 * st.text_h * size
    v = math.ceil(lo / (step / 2) - 1e-9) * step / 2
    while v <= hi + 1e-9:
        major = abs(v / step - round(v / step)) < 1e-6
        ang = st.angle_of(v / k)
        ux, uy = direction(ang)
        ln = (0.03 if major else 0.016) * size
        red.poly([(c + ux * r2 - uy * 0.6, c + uy * r2 + ux * 0.6),
                  (c + ux * (r2 - ln) - uy * 0.5, c + uy * (r2 - ln) + ux * 0.5),
                  (c + ux * (r2 - ln) + uy * 0.5, c + uy * (r2 - ln) - ux * 0.5),
                  (c + ux * r2 + uy * 0.6, c + uy * r2 - ux * 0.6)])
        if major:
            txt = _fmt(v)
            half = 0.5 * math.hypot(text_width(txt, h), h) * 0.85
            rn = r2 - 0.03 * size - 0.012 * size - half
            typeset(red, txt, c + ux * rn, c + uy * rn, h, 0.12)
        v += step / 2


def _labels(st, size: int, ink: Ink, red: Ink) -> None:
    c = size / 2.0
    r_in, _ = (v * size for v in st.tick_span())
    h = st.text_h * size
    lowest = r_in
    for i, (v, ang, _) in enumerate(t for t in st.tick_list() if t[2] == "major"):
        if i % st.label_every:
            continue
        txt = _fmt(v)
        half = 0.5 * math.hypot(text_width(txt, h), h) * 0.85
        rn = r_in - 0.02 * size - half
        lowest = min(lowest, rn - half)
        ux, uy = direction(ang)
        typeset(ink, txt, c + ux * rn, c + uy * rn, h, st.text_weight)
    wide = abs(st.max_angle_deg - st.min_angle_deg) > 280
    if st.second_scale:
        _second_scale(st, size, lowest - 0.025 * size, red)
        typeset(ink, _printed(st.unit), c, c + 0.085 * size, 0.75 * h, 0.12)
        typeset(red, _printed(st.second_unit), c, c + 0.14 * size, 0.62 * h, 0.12)
        if st.brand:
            typeset(ink, st.brand, c, c - 0.075 * size, 0.022 * size, 0.13)
        return
    typeset(ink, _printed(st.unit), c, c + (0.15 if wide else 0.17) * size, 0.85 * h, 0.12)
    if st.brand:
        typeset(ink, st.brand, c, c - 0.13 * size, 0.028 * size, 0.13)
    if st.logo == "crest":  # a small shield outline with the maker's initial
        q, y0 = 0.022 * size, c - 0.19 * size
        pts = [(c - q, y0 - q), (c + q, y0 - q), (c + q, y0 + 0.2 * q), (c, y0 + 1.2 * q),
               (c - q, y0 + 0.2 * q)]
        for a, b in zip(pts, pts[1:] + pts[:1], strict=True):
            rule(ink, a, b, max(0.8, 0.12 * q))
        typeset(ink, st.brand[:1], c, y0 - 0.05 * q, 1.1 * q, 0.16)
    if st.face_print == "class":  # the accuracy class and the standard
        cl = f"CL {1.0 if st.texture_seed % 3 == 0 else 1.6}"
        if wide:  # the bottom is narrow between the end numerals: one line, higher up
            typeset(ink, f"{cl}  EN 837-1", c, c + 0.088 * size, 0.017 * size, 0.13)
        else:
            typeset(ink, cl, c, c + 0.225 * size, 0.02 * size, 0.13)
            typeset(ink, "EN 837-1", c, c + 0.255 * size, 0.017 * size, 0.13)


def needle_outline(shape: str, L: float, w: float, T: float) -> list[list[tuple[float, float]]]:
    """Needle polygons in (along, across) coordinates, tip at (L, 0), pivot at the origin."""
    if shape == "lancet":  # a blade to a sharp point, a tail ending in a teardrop
        bulb = [(-0.8 * T + 2.1 * w * math.cos(t), 1.7 * w * math.sin(t))
                for t in np.linspace(0, 2 * math.pi, 20, endpoint=False)]
        return [[(-0.8 * T, -0.5 * w), (0, -w), (0.75 * L, -0.45 * w), (L, 0.0),
                 (0.75 * L, 0.45 * w), (0, w), (-0.8 * T, 0.5 * w)], bulb]
    if shape == "lozenge":  # widest at the pivot, tapering to both ends
        return [[(-T, 0.0), (0, -1.35 * w), (L, -0.05 * w), (L, 0.05 * w), (0, 1.35 * w)]]
    # spear: a fine shaft and a slim head near the tip, a stub of a tail
    return [[(-T, -0.6 * w), (0.78 * L, -0.55 * w), (0.84 * L, -1.3 * w), (L, 0.0),
             (0.84 * L, 1.3 * w), (0.78 * L, 0.55 * w), (-T, 0.6 * w)]]


def _needle(img: np.ndarray, st, size: int, ang: float, light) -> None:
    c = size / 2.0
    L, w, T = st.needle_len * size, st.needle_width * size / 2, st.tail_len * size
    ux, uy = direction(ang)
    nx, ny = -uy, ux
    polys = [[(c + ux * s + nx * t, c + uy * s + ny * t) for s, t in poly]
             for poly in needle_outline(st.needle_shape, L, w, T)]
    needle_shadow(img, polys, light, 0.012 * size)
    m = Ink(size, st.needle_bgr)
    for poly in polys:
        m.poly(poly)
    m.lay(img, 1.0, 0)
    if st.needle_shape != "lancet":
        return
    ridge = Ink(size, tuple(min(255, v + 70) for v in st.needle_bgr))  # light along the blade
    rule(ridge, (c + ux * 0.1 * L, c + uy * 0.1 * L), (c + ux * 0.7 * L, c + uy * 0.7 * L),
                 max(0.5, 0.3 * w))
    ridge.lay(img, 0.5, 0)


def _dome(img: np.ndarray, c: float, r: float, colour, light) -> None:
    """A domed hub cap, shaded as a sphere lit from ``light`` with a specular spot."""
    size = img.shape[0]
    yy, xx = np.mgrid[0:size, 0:size].astype(np.float32)
    u, v = (xx - c) / r, (yy - c) / r
    z = np.sqrt(np.clip(1 - u * u - v * v, 0, 1))
    lx, ly = -light[0], -light[1]
    lz = 1.2
    n = math.sqrt(lx * lx + ly * ly + lz * lz)
    lam = np.clip((u * lx + v * ly + z * lz) / n, 0, 1)
    spec = lam ** 30 * 120
    cap = np.array(colour, np.float32)[None, None, :] * (0.35 + 0.75 * lam)[..., None]
    cap += spec[..., None]
    a = _disc_alpha(size, c, r)
    img *= 1 - a
    img += a * cap


def _drag(img, st, size: int) -> None:
    """The red mark pointer on the glass, turned by the knob in the glass's centre."""
    c = size / 2.0
    ang = st.angle_of(st.setpoint)
    ux, uy = direction(ang)
    L = 0.96 * st.needle_len * size
    red = Ink(size, FOUNDRY_RED)
    rule(red, (c - ux * 0.06 * L, c - uy * 0.06 * L), (c + ux * L, c + uy * L), 1.4)
    red.lay(img, 1.0, 0)
    _dome(img, c, 1.5 * st.hub_radius * size, FOUNDRY_RED, (0.5, 0.7))


def draw_dial(st, value: float, size: int = 300) -> tuple[np.ndarray, dict]:
    """The upright foundry dial showing ``value``: ``(BGR uint8 crop, ground truth)``,
    the truth as :func:`sim_robot.gauge_dial.draw_dial` gives it."""
    c = size / 2.0
    rng = np.random.default_rng([st.texture_seed, size])
    la = rng.uniform(0, 2 * np.pi)
    light = (math.cos(la), math.sin(la))  # the direction the light falls across the face
    img = _case(st, size, rng)
    face = _face(st, size, rng, light)
    ink, red = Ink(size, st.ink_bgr), Ink(size, FOUNDRY_RED)
    _ticks(st, size, ink, red, face)
    _labels(st, size, ink, red)
    red.lay(face, 0.92)
    ink.lay(face, 0.95)
    if st.stop_pin:  # a turned steel pin, its shadow away from the light
        pa, rp, pr = _pin(st, size)
        px, py = c + direction(pa)[0] * rp, c + direction(pa)[1] * rp
        for dx, colour, r in ((0.35, (60, 60, 62), pr), (0.0, (150, 152, 156), pr),
                              (-0.3, (220, 222, 225), 0.35 * pr)):
            dot = Ink(size, colour)
            dot.disc((px + dx * pr * light[0], py + dx * pr * light[1]), r)
            dot.lay(face, 1.0, 0)
    ang = needle_angle(st, value, size)
    _needle(face, st, size, ang, light)
    _dome(face, c, st.hub_radius * size, st.hub_bgr, light)
    if st.setpoint is not None:
        _drag(face, st, size)
    glass(face, st, size, rng, light)
    a = _disc_alpha(size, c, st.face_radius * size)
    img = np.clip(img * (1 - a) + face * a, 0, 255).astype(np.uint8)
    r_in, r_out = st.tick_span()
    rm = (r_in + r_out) / 2 * size
    marks = [(c + direction(q)[0] * rm, c + direction(q)[1] * rm)
             for q in (st.min_angle_deg, st.max_angle_deg)]
    truth = {"value": float(min(max(value, st.min_value), st.max_value)),
             "needle_angle_deg": ang, "pivot_xy": (c, c), "min_mark_xy": marks[0],
             "max_mark_xy": marks[1], "scale_radius_px": rm,
             "needle_len_px": st.needle_len * size}
    return img, truth
