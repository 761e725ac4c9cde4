"""Drawing of :class:`~sim_robot.gauge_styles.DialStyle` dials, with their ground truth.

Qt-free: numpy + OpenCV only.  Angles are degrees clockwise from 12 o'clock on the upright
dial.  :func:`draw_dial` paints bezel, face (and its printed texture), colour zones, arcs,
ticks, numerals, unit, brand and logo, an optional second scale, the red set-point
pointer, the stop pin, the needle and its hub cap, and returns the pivot, the scale's end
marks and the needle's drawn angle in crop pixels.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from . import gauge_atlas as atlas
from . import gauge_foundry as foundry
from .gauge_draw import SC as _SC
from .gauge_draw import SH as _SH
from .gauge_draw import direction as _dir
from .gauge_draw import p as _p
from .gauge_styles import BLOCK_FONT, DOT_FONT, RED, SEGMENT_FONT, DialStyle

__all__ = ["draw_dial", "needle_angle", "outline_mask"]

# ----------------------------------------------------------------------------- drawing


def _blend_disc(img: np.ndarray, layer: np.ndarray, radius: float) -> np.ndarray:
    """``layer`` inside an anti-aliased disc of ``radius`` about the centre, ``img`` outside."""
    size = img.shape[0]
    m = np.zeros((size, size), np.uint8)
    cv2.circle(m, _p(size / 2, size / 2), int(radius * _SC), 255, -1, cv2.LINE_AA, _SH)
    a = m.astype(np.float32)[..., None] / 255.0
    return (img.astype(np.float32) * (1 - a) + layer * a).astype(np.uint8)


def _radial(size: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    c = size / 2.0
    yy, xx = np.mgrid[0:size, 0:size].astype(np.float32)
    return xx - c, yy - c, np.hypot(xx - c, yy - c) / size


def _hexagon(size: int) -> np.ndarray:
    c, r = size / 2.0, 0.49 * size
    return np.array([_p(c + r * math.cos(math.radians(60 * k)),
                        c + r * math.sin(math.radians(60 * k))) for k in range(6)], np.int32)


def outline_mask(style: DialStyle, size: int) -> np.ndarray:
    """The gauge's outline in its crop (255 inside, anti-aliased): the hexagonal flange of
    a ``hex`` bezel, else the round case of radius 0.49 ``size``."""
    m = np.zeros((size, size), np.uint8)
    if style.bezel_kind == "hex":
        cv2.fillPoly(m, [_hexagon(size)], 255, cv2.LINE_AA, _SH)
    else:
        cv2.circle(m, _p(size / 2, size / 2), int(0.49 * size * _SC), 255, -1, cv2.LINE_AA, _SH)
    return m


def _bezel(st: DialStyle, size: int) -> np.ndarray:
    img = np.full((size, size, 3), 255, np.uint8)
    if st.bezel_kind == "none":
        return img
    if st.bezel_kind == "hex":  # a hexagonal flange, flat on top, with a darker edge
        hexa = _hexagon(size)
        cv2.fillPoly(img, [hexa], st.bezel_bgr, cv2.LINE_AA, _SH)
        cv2.polylines(img, [hexa], True, tuple(int(0.6 * v) for v in st.bezel_bgr),
                      max(1, size // 150), cv2.LINE_AA, _SH)
        return img
    dx, dy, rr = _radial(size)
    col = np.array(st.bezel_bgr, np.float32)
    if st.bezel_kind == "knurled":  # fine radial serrations, a dark inner lip
        teeth = np.cos(np.arctan2(dy, dx) * 90.0)
        lip = np.exp(-(((rr - st.face_radius - 0.012) / 0.006) ** 2))
        layer = col[None, None, :] * (0.85 + 0.2 * teeth[..., None]) * (1 - 0.5 * lip[..., None])
    elif st.bezel_kind == "bayonet":
        layer = atlas.bezel_layer(col, dx, dy, rr, size)
    elif st.bezel_kind in ("chrome", "brass"):  # light from the upper left: a gradient ring
        lit = (-(dx + dy) / (size * 0.7)).clip(-1, 1)
        ring = np.cos((rr - 0.47) * 60.0)[..., None]
        layer = col[None, None, :] * (0.75 + 0.35 * lit[..., None]) + 40 * ring
    else:
        layer = np.broadcast_to(col, (size, size, 3)).astype(np.float32)
    return _blend_disc(img, np.clip(layer, 0, 255), 0.49 * size)


def _face(st: DialStyle, img: np.ndarray, size: int) -> np.ndarray:
    dx, dy, rr = _radial(size)
    col = np.array(st.face_bgr, np.float32)[None, None, :]
    shade = 1.0 - 0.07 * (rr / st.face_radius) ** 2
    layer = col * shade[..., None]
    trng = np.random.default_rng(st.texture_seed)
    if st.face_kind == "texture":  # brushed metal: streaks along x, or printed fine rings
        if trng.random() < 0.5:
            streak = cv2.blur(trng.normal(0, 14, (size, size)).astype(np.float32), (25, 1))
        else:
            streak = 6.0 * np.sin(rr * size * trng.uniform(0.8, 1.6)).astype(np.float32)
        layer = layer + streak[..., None]
    elif st.face_kind == "parchment":  # mottled, low-frequency printed texture, dark edges
        small = trng.normal(0, 1, (12, 12)).astype(np.float32)
        mott = cv2.resize(small, (size, size), interpolation=cv2.INTER_CUBIC)
        layer = layer * (1 + 0.05 * mott[..., None]) * (1 - 0.18 * (rr / 0.45) ** 4)[..., None]
    elif st.face_kind == "sunburst":  # fine radial rays, brighter toward the centre
        rays = np.cos(np.arctan2(dy, dx) * 120.0).astype(np.float32)
        layer = layer * (1.12 - 0.25 * (rr / st.face_radius))[..., None] + 5.0 * rays[..., None]
    elif st.face_kind in ("powder", "carbon"):
        layer = atlas.face_layer(st.face_kind, layer, dx, dy, rr, st.face_radius, trng)
    elif st.face_kind == "two-tone" and st.face_low_bgr is not None:  # a tinted lower band
        low = np.array(st.face_low_bgr, np.float32)[None, None, :] * shade[..., None]
        t = np.clip((dy / size - 0.12) / 0.01, 0, 1)[..., None]  # a soft print edge
        layer = layer * (1 - t) + low * t
    img = _blend_disc(img, np.clip(layer, 0, 255), st.face_radius * size)
    if st.bezel_kind in ("screws", "brass"):
        c = size / 2
        n = 4 if st.bezel_kind == "screws" else 6
        for k in range(n):
            a = 45.0 + k * 360.0 / n
            sx, sy = _dir(a)
            r = (0.49 + st.face_radius) / 2 * size
            px, py = c + sx * r, c + sy * r
            cv2.circle(img, _p(px, py), int(0.014 * size * _SC), (200, 200, 205), -1,
                       cv2.LINE_AA, _SH)
            q = 0.012 * size
            cv2.line(img, _p(px - q, py + q * 0.3), _p(px + q, py - q * 0.3), (60, 60, 60),
                     max(1, size // 300), cv2.LINE_AA, _SH)
    return img


def _arc(img, c, r, a0, a1, colour, th):
    lo, hi = sorted((a0, a1))
    cv2.ellipse(img, _p(c, c), (int(r * _SC), int(r * _SC)), 0, lo - 90, hi - 90, colour,
                max(1, int(round(th))), cv2.LINE_AA, _SH)


def _ticks(st: DialStyle, img: np.ndarray, size: int) -> None:
    c = size / 2
    r_in, r_out = (v * size for v in st.tick_span())
    lw = st.tick_width * size
    if st.zone_kind == "rim":  # sectors outside the ticks
        atlas.rim_zones(img, c, r_out + 0.008 * size, r_out + 0.03 * size, st.zones, st.angle_of)
    for v0, v1, col in st.zones if st.zone_kind == "arc" else ():
        rz = st.scale_radius * size - (st.tick_len * size * 0.5 if st.arc != "outside" else 0)
        _arc(img, c, rz, st.angle_of(v0), st.angle_of(v1), col, st.tick_len * size * 0.55)
    if st.arc in ("inside", "outside", "crossing"):
        _arc(img, c, st.scale_radius * size, st.min_angle_deg, st.max_angle_deg, st.ink_bgr,
             lw * 0.8)
    elif st.arc == "double":
        for r in (r_in, r_out):
            _arc(img, c, r, st.min_angle_deg, st.max_angle_deg, st.ink_bgr, lw * 0.6)
    elif st.arc == "rail":  # two fine arcs, every other major interval filled between them
        for r in (r_in, r_out):
            _arc(img, c, r, st.min_angle_deg, st.max_angle_deg, st.ink_bgr, lw * 0.45)
        majors = [a for _, a, k in st.tick_list() if k == "major"]
        for a0, a1 in list(zip(majors[:-1], majors[1:], strict=True))[::2]:
            _arc(img, c, r_in + (r_out - r_in) * 0.8, a0, a1, st.ink_bgr,
                 (r_out - r_in) * 0.3)
    elif st.arc == "segmented":  # broken round every major tick, at the ticks' outer end
        atlas.segmented_arc(img, c, r_out, [a for _, a, k in st.tick_list() if k == "major"],
                            lw * 0.7, st.ink_bgr)
    elif st.arc == "band" and st.band_bgr is not None:  # a tinted band under the ticks
        _arc(img, c, (r_in + r_out) / 2, st.min_angle_deg, st.max_angle_deg, st.band_bgr,
             (r_out - r_in) * 1.3)
    for _v, ang, kind in st.tick_list():
        dx, dy = _dir(ang)
        nx, ny = -dy, dx
        frac = {"major": 1.0, "medium": 0.7, "minor": 0.45}[kind]
        a_in = r_out - (r_out - r_in) * frac if st.arc != "outside" else r_in
        a_out = a_in + (r_out - r_in) * frac
        if st.arc == "crossing":
            mid = (r_in + r_out) / 2
            a_in, a_out = mid - (r_out - r_in) * frac / 2, mid + (r_out - r_in) * frac / 2
        shape = st.major_kind if kind == "major" else st.minor_kind
        w = lw * (1.0 if kind == "major" else 0.6)
        if shape in ("tee", "spike"):
            atlas.draw_tick(img, c, ang, shape, a_in, a_out, w, st.ink_bgr)
        elif shape == "ring":  # a hollow circle centred in the tick's span
            rm = (a_in + a_out) / 2
            cv2.circle(img, _p(c + dx * rm, c + dy * rm), int(max(2.0, 1.6 * w) * _SC),
                       st.ink_bgr, max(1, int(round(0.6 * w))), cv2.LINE_AA, _SH)
        elif shape == "tangent":  # a short dash across the ray, at the span's outer part
            rm, q = a_out - 0.3 * (a_out - a_in), max(1.5, 1.8 * w)
            cv2.line(img, _p(c + dx * rm - nx * q, c + dy * rm - ny * q),
                     _p(c + dx * rm + nx * q, c + dy * rm + ny * q), st.ink_bgr,
                     max(1, int(round(0.8 * w))), cv2.LINE_AA, _SH)
        elif shape == "dot":
            rm = (a_in + a_out) / 2
            rad = max(1.0, w * (1.1 if kind == "major" else 0.9))
            cv2.circle(img, _p(c + dx * rm, c + dy * rm), int(rad * _SC), st.ink_bgr, -1,
                       cv2.LINE_AA, _SH)
        elif shape in ("diamond", "square"):  # a rhombus along the ray; a small square
            rm, half = (a_in + a_out) / 2, (a_out - a_in) / 2
            q = 1.5 * w if shape == "diamond" else max(1.0, 1.1 * w)
            pts = ([(rm - half, 0.0), (rm, -q), (rm + half, 0.0), (rm, q)] if shape == "diamond"
                   else [(rm - q, -q), (rm + q, -q), (rm + q, q), (rm - q, q)])
            poly = np.array([_p(c + dx * s + nx * t, c + dy * s + ny * t) for s, t in pts],
                            np.int32)
            cv2.fillPoly(img, [poly], st.ink_bgr, cv2.LINE_AA, _SH)
        elif shape == "wedge":  # wide at the scale's edge, pointed toward the centre
            wide = 1.4 * w
            pts = [(a_out, -wide), (a_out, wide), (a_in, 0.0)]
            poly = np.array([_p(c + dx * s + nx * t, c + dy * s + ny * t) for s, t in pts],
                            np.int32)
            cv2.fillPoly(img, [poly], st.ink_bgr, cv2.LINE_AA, _SH)
        else:
            cv2.line(img, _p(c + dx * a_in, c + dy * a_in), _p(c + dx * a_out, c + dy * a_out),
                     st.ink_bgr, max(1, int(round(w))), cv2.LINE_AA, _SH)


def _fmt(v: float) -> str:
    s = f"{v:.2f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


# seven segments a..g of a glyph 0.6 wide and 1 high (x right, y down, top-left origin)
_SEGS = {"a": ((0, 0), (1, 0)), "b": ((1, 0), (1, 0.5)), "c": ((1, 0.5), (1, 1)),
         "d": ((0, 1), (1, 1)), "e": ((0, 0.5), (0, 1)), "f": ((0, 0), (0, 0.5)),
         "g": ((0, 0.5), (1, 0.5))}
_GLYPHS = {"0": "abcdef", "1": "bc", "2": "abdeg", "3": "abcdg", "4": "bcfg", "5": "acdfg",
           "6": "acdefg", "7": "abc", "8": "abcdefg", "9": "abcdfg", "-": "g", "A": "abcefg",
           "B": "cdefg", "C": "adef", "D": "bcdeg", "E": "adefg", "F": "aefg", "G": "acdef",
           "H": "bcefg", "I": "ef", "J": "bcd", "K": "bcefg", "L": "def", "M": "abcef",
           "N": "ceg", "O": "cdeg", "P": "abefg", "R": "eg", "S": "acdfg", "T": "defg",
           "U": "bcdef", "W": "bcdef", "Y": "bcdfg", "Z": "abdeg"}


def _segment_text(img, txt, x, y, height_px: float, colour, th: int) -> None:
    """Seven-segment glyphs: ``(x, y)`` is the bottom-left corner, as for cv2.putText."""
    gw = 0.55 * height_px
    for ch in txt:
        if ch == ".":
            cv2.circle(img, _p(x + 0.1 * gw, y), int(th * 0.8 * _SC), colour, -1, cv2.LINE_AA,
                       _SH)
            x += 0.4 * gw
            continue
        for seg in _GLYPHS.get(ch.upper(), "" if ch == " " else "adg"):
            (x0, y0), (x1, y1) = _SEGS[seg]
            cv2.line(img, _p(x + x0 * gw, y - height_px + y0 * height_px),
                     _p(x + x1 * gw, y - height_px + y1 * height_px), colour, th, cv2.LINE_AA,
                     _SH)
        x += 1.45 * gw


# dot-matrix glyphs, 5 columns x 7 rows, one string of five bits per row (top first)
_DOTS = {"0": ("01110", "10001", "10011", "10101", "11001", "10001", "01110"),
         "1": ("00100", "01100", "00100", "00100", "00100", "00100", "01110"),
         "2": ("01110", "10001", "00001", "00010", "00100", "01000", "11111"),
         "3": ("11110", "00001", "00001", "01110", "00001", "00001", "11110"),
         "4": ("00010", "00110", "01010", "10010", "11111", "00010", "00010"),
         "5": ("11111", "10000", "11110", "00001", "00001", "10001", "01110"),
         "6": ("00110", "01000", "10000", "11110", "10001", "10001", "01110"),
         "7": ("11111", "00001", "00010", "00100", "01000", "01000", "01000"),
         "8": ("01110", "10001", "10001", "01110", "10001", "10001", "01110"),
         "9": ("01110", "10001", "10001", "01111", "00001", "00010", "01100"),
         "-": ("00000", "00000", "00000", "11111", "00000", "00000", "00000"),
         ".": ("00000", "00000", "00000", "00000", "00000", "01100", "01100"),
         "A": ("01110", "10001", "10001", "11111", "10001", "10001", "10001"),
         "B": ("11110", "10001", "10001", "11110", "10001", "10001", "11110"),
         "C": ("01110", "10001", "10000", "10000", "10000", "10001", "01110"),
         "D": ("11110", "10001", "10001", "10001", "10001", "10001", "11110"),
         "E": ("11111", "10000", "10000", "11110", "10000", "10000", "11111"),
         "F": ("11111", "10000", "10000", "11110", "10000", "10000", "10000"),
         "G": ("01110", "10001", "10000", "10111", "10001", "10001", "01111"),
         "I": ("01110", "00100", "00100", "00100", "00100", "00100", "01110"),
         "J": ("00111", "00010", "00010", "00010", "00010", "10010", "01100"),
         "K": ("10001", "10010", "10100", "11000", "10100", "10010", "10001"),
         "L": ("10000", "10000", "10000", "10000", "10000", "10000", "11111"),
         "M": ("10001", "11011", "10101", "10101", "10001", "10001", "10001"),
         "O": ("01110", "10001", "10001", "10001", "10001", "10001", "01110"),
         "P": ("11110", "10001", "10001", "11110", "10000", "10000", "10000"),
         "R": ("11110", "10001", "10001", "11110", "10100", "10010", "10001"),
         "S": ("01111", "10000", "10000", "01110", "00001", "00001", "11110")}
_DOT_FALLBACK = ("11111", "10001", "10001", "10001", "10001", "10001", "11111")


def _dot_text(img, txt, x, y, height_px: float, colour) -> None:
    """Dot-matrix glyphs: ``(x, y)`` is the bottom-left corner, as for cv2.putText."""
    pitch = height_px / 6.5
    rad = max(0.6, 0.3 * pitch)
    for ch in txt:
        rows = _DOTS.get(ch.upper(), () if ch == " " else _DOT_FALLBACK)
        for j, row in enumerate(rows):
            for i, bit in enumerate(row):
                if bit == "1":
                    cv2.circle(img, _p(x + (i + 0.5) * pitch, y - height_px + (j + 0.25) * pitch),
                               int(rad * _SC), colour, -1, cv2.LINE_AA, _SH)
        x += _DOT_ADVANCE * pitch


_DOT_ADVANCE = 5.6  # glyph pitch in dots (five dots and a narrow space)


def _dot_width(txt: str, height_px: float) -> float:
    return len(txt) * _DOT_ADVANCE * height_px / 6.5


def _text(img, txt, x, y, st: DialStyle, height_px: float, colour, centred=True,
          angle_deg: float = 0.0) -> None:
    if st.font == BLOCK_FONT:  # always centred on (x, y)
        atlas.block_text(img, txt, x, y, height_px, colour, angle_deg)
        return
    if st.font == DOT_FONT:
        if centred:
            x, y = x - _dot_width(txt, height_px) / 2, y + height_px / 2
        _dot_text(img, txt, x, y, height_px, colour)
        return
    if st.font == SEGMENT_FONT:
        th = max(1, int(round(st.text_weight * img.shape[0] * height_px / (0.045 * img.shape[0]))))
        n = sum(0.4 if ch == "." else 1.45 for ch in txt)
        tw = n * 0.55 * height_px
        if centred:
            x, y = x - tw / 2, y + height_px / 2
        _segment_text(img, txt, x, y, height_px, colour, th)
        return
    font = st.font | (cv2.FONT_ITALIC if st.italic else 0)
    (_, h1), _ = cv2.getTextSize("0", font, 1.0, 1)
    scale = height_px / max(h1, 1)
    th = max(1, int(round(st.text_weight * img.shape[0] * height_px / (0.045 * img.shape[0]))))
    (tw, thh), _ = cv2.getTextSize(txt, font, scale, th)
    if centred:
        x, y = x - tw / 2, y + thh / 2
    cv2.putText(img, txt, (int(x), int(y)), font, scale, colour, th, cv2.LINE_AA)


def _labels(st: DialStyle, img: np.ndarray, size: int) -> None:
    c = size / 2
    r_in, r_out = (v * size for v in st.tick_span())
    h = st.text_h * size
    if st.numerals != "none":
        majors = [t for t in st.tick_list() if t[2] == "major"]
        for i, (v, ang, _) in enumerate(majors):
            if i % st.label_every:
                continue
            dx, dy = _dir(ang)
            txt = _fmt(v)
            if st.font == BLOCK_FONT:
                tw = atlas.block_width(txt, h)
            elif st.font == DOT_FONT:
                tw = _dot_width(txt, h)
            elif st.font == SEGMENT_FONT:
                tw = sum(0.4 if ch == "." else 1.45 for ch in txt) * 0.55 * h
            else:
                font = st.font | (cv2.FONT_ITALIC if st.italic else 0)
                (tw, _), _ = cv2.getTextSize(txt, font, h / 22.0, 1)
            radial = st.numeral_orient == "radial"  # turned: the text's height lies radially
            half = 0.5 * h * 1.1 if radial else 0.5 * math.hypot(tw, h) * 0.9
            rn = (r_in - 0.02 * size - half if st.numerals == "inside"
                  else r_out + 0.02 * size + half)
            _text(img, txt, c + dx * rn, c + dy * rn, st, h, st.ink_bgr,
                  angle_deg=ang if radial else 0.0)
    if st.second_scale:
        r2 = r_in - 0.16 * size
        for v, ang, kind in st.tick_list():
            if kind != "major":
                continue
            dx, dy = _dir(ang)
            _text(img, _fmt(round(v * st.second_scale)), c + dx * r2, c + dy * r2, st, h * 0.6,
                  RED)
    uy = atlas.unit_y(st, size) if st.font == BLOCK_FONT else c + 0.2 * size
    _text(img, st.unit, c, uy, st, h * 0.9, st.ink_bgr)
    if st.brand:
        _text(img, st.brand, c, c - 0.14 * size, st, h * 0.7, st.ink_bgr)
    if st.logo == "fan":
        atlas.face_print(img, st, size)
    elif st.logo != "none":
        lx, ly, q = c, c - 0.21 * size, 0.025 * size
        th = max(1, size // 200)
        if st.logo == "circle":
            cv2.circle(img, _p(lx, ly), int(q * _SC), st.ink_bgr, th, cv2.LINE_AA, _SH)
            _text(img, st.brand[:1] or "G", lx, ly, st, q, st.ink_bgr)
        elif st.logo == "bars":  # three stacked bars, the middle one longest
            for k, f in ((-1, 0.7), (0, 1.0), (1, 0.7)):
                cv2.rectangle(img, _p(lx - f * q, ly + k * 0.7 * q - 0.22 * q),
                              _p(lx + f * q, ly + k * 0.7 * q + 0.22 * q), st.ink_bgr, -1,
                              cv2.LINE_AA, _SH)
        elif st.logo == "star":
            pts = [(lx + (q if k % 2 == 0 else 0.45 * q) * math.sin(math.radians(36 * k)),
                    ly - (q if k % 2 == 0 else 0.45 * q) * math.cos(math.radians(36 * k)))
                   for k in range(10)]
            cv2.fillPoly(img, [np.array([_p(*p) for p in pts], np.int32)], st.ink_bgr,
                         cv2.LINE_AA, _SH)
        else:
            pts = ([(lx, ly - q), (lx + q, ly), (lx, ly + q), (lx - q, ly)] if st.logo == "diamond"
                   else [(lx, ly - q), (lx + q, ly + q * 0.8), (lx - q, ly + q * 0.8)])
            cv2.fillPoly(img, [np.array([_p(*p) for p in pts], np.int32)], st.ink_bgr,
                         cv2.LINE_AA, _SH)


def _needle_poly(shape: str, L: float, w: float, T: float) -> list[list[tuple[float, float]]]:
    """Polygons in (along, across) needle coordinates: tip at (L, 0), pivot at the origin."""
    if shape == "arrow":
        return [[(0, -w * 0.8), (L - 4 * w, -w * 0.5), (L - 4 * w, -w * 1.8), (L, 0),
                 (L - 4 * w, w * 1.8), (L - 4 * w, w * 0.5), (0, w * 0.8), (-T, w), (-T, -w)]]
    if shape == "lance":
        return [[(0, -w * 1.3), (0.55 * L, -w * 1.1), (L, 0), (0.55 * L, w * 1.1), (0, w * 1.3),
                 (-T, w * 1.3), (-T, -w * 1.3)]]
    if shape == "arrow-tail":  # thin tip, a tail that widens into feathers wider than the tip
        return [[(0, -w * 0.7), (L, -0.1 * w), (L, 0.1 * w), (0, w * 0.7), (-0.6 * T, w * 1.2),
                 (-T, w * 2.6), (-0.85 * T, 0), (-T, -w * 2.6), (-0.6 * T, -w * 1.2)]]
    if shape == "spade":  # shaft, a spade head near the tip, a fine point
        sh = 0.55 * w
        return [[(0, -sh), (0.62 * L, -sh), (0.72 * L, -2.6 * w), (0.82 * L, -sh * 0.6),
                 (L, -0.08 * w), (L, 0.08 * w), (0.82 * L, sh * 0.6), (0.72 * L, 2.6 * w),
                 (0.62 * L, sh), (0, sh), (-T, sh), (-T, -sh)]]
    if shape == "baton":  # parallel-sided bar with a short point, a square counterweight
        return [[(-T, -0.6 * w), (L - 2.5 * w, -0.6 * w), (L, 0), (L - 2.5 * w, 0.6 * w),
                 (-T, 0.6 * w)],
                [(-T, -1.8 * w), (-T + 3.6 * w, -1.8 * w), (-T + 3.6 * w, 1.8 * w),
                 (-T, 1.8 * w)]]
    if shape == "sword":  # a blade widening to mid-length, a cross-guard; pommel apart
        return [[(0, -0.5 * w), (0.5 * L, -1.1 * w), (L, 0), (0.5 * L, 1.1 * w), (0, 0.5 * w),
                 (-T, 0.45 * w), (-T, -0.45 * w)],
                [(0.12 * L, -2.2 * w), (0.12 * L + 1.2 * w, -2.2 * w),
                 (0.12 * L + 1.2 * w, 2.2 * w), (0.12 * L, 2.2 * w)]]
    if shape in atlas.ATLAS_NEEDLES:
        return atlas.needle_polys(shape, L, w, T)
    taper = [(0, -w), (L, -0.12 * w), (L, 0.12 * w), (0, w), (-T, w * 1.1), (-T, -w * 1.1)]
    return [taper]  # thin, two-ended (the counterweight is drawn apart)


def _pointer(img, c, angle, shape, L, w, T, colour) -> None:
    dx, dy = _dir(angle)
    nx, ny = -dy, dx
    for poly in _needle_poly(shape, L, w, T):
        pts = np.array([_p(c + dx * s + nx * t, c + dy * s + ny * t) for s, t in poly], np.int32)
        cv2.fillPoly(img, [pts], colour, cv2.LINE_AA, _SH)
    if shape == "two-ended":  # a counterweight disc on the tail
        q = -0.85 * T
        cv2.circle(img, _p(c + dx * q, c + dy * q), int(2.2 * w * _SC), colour, -1, cv2.LINE_AA,
                   _SH)
    elif shape == "sword":  # a pommel disc at the tail's end
        cv2.circle(img, _p(c - dx * T, c - dy * T), int(1.7 * w * _SC), colour, -1, cv2.LINE_AA,
                   _SH)
    elif shape == "spade":  # a ring counterweight
        q = -0.8 * T
        cv2.circle(img, _p(c + dx * q, c + dy * q), int(2.4 * w * _SC), colour,
                   max(1, int(round(w))), cv2.LINE_AA, _SH)


def needle_angle(style: DialStyle, value: float) -> float:
    """The angle at which the needle is drawn for ``value``: on the stop pin at the minimum."""
    if style.family == foundry.FOUNDRY:  # its own renderer
        return foundry.needle_angle(style, value)
    if style.stop_pin and value <= style.min_value:
        return style.pin_angle_deg + style.direction * 3.0
    return style.angle_of(value)


def draw_dial(style: DialStyle, value: float, size: int = 300) -> tuple[np.ndarray, dict]:
    """Upright dial showing ``value``: ``(BGR uint8 crop, ground truth in crop pixels)``.

    The truth holds ``value``, ``needle_angle_deg``, ``pivot_xy`` (the crop centre),
    ``min_mark_xy``/``max_mark_xy`` (the middle of the end marks' major ticks) and
    ``scale_radius_px`` (the radius of those points).
    """
    if style.family == foundry.FOUNDRY:  # its own renderer
        return foundry.draw_dial(style, value, size)
    c = size / 2.0
    img = _bezel(style, size)
    img = _face(style, img, size)
    _ticks(style, img, size)
    _labels(style, img, size)
    L, w, T = style.needle_len * size, style.needle_width * size / 2, style.tail_len * size
    if style.setpoint is not None and style.setpoint_kind == "flag":
        atlas.flag_setpoint(img, c, style.angle_of(style.setpoint), L, w,
                            style.hub_radius * size)
    elif style.setpoint is not None:  # the red set-point pointer lies under the needle
        _pointer(img, c, style.angle_of(style.setpoint), "lance", 0.9 * L, 0.6 * w, 0.0, RED)
        cv2.circle(img, _p(c, c), int(1.4 * style.hub_radius * size * _SC), RED, -1,
                   cv2.LINE_AA, _SH)
    if style.stop_pin:
        pdx, pdy = _dir(style.pin_angle_deg)
        pr = 0.7 * L
        cv2.circle(img, _p(c + pdx * pr, c + pdy * pr), int(0.011 * size * _SC), (90, 90, 95), -1,
                   cv2.LINE_AA, _SH)
    ang = needle_angle(style, value)
    _pointer(img, c, ang, style.needle_shape, L, w, T, style.needle_bgr)
    hub_r = style.hub_radius * size
    if style.hub_kind == "nut":
        atlas.nut_hub(img, c, hub_r, style.hub_bgr)
    else:
        cv2.circle(img, _p(c, c), int(hub_r * _SC), style.hub_bgr, -1, cv2.LINE_AA, _SH)
        hl = tuple(int(min(255, v + 70)) for v in style.hub_bgr)
        cv2.circle(img, _p(c - hub_r * 0.3, c - hub_r * 0.3), int(hub_r * 0.3 * _SC), hl, -1,
                   cv2.LINE_AA, _SH)
    r_in, r_out = style.tick_span()
    rm = (r_in + r_out) / 2 * size
    marks = [(c + _dir(a)[0] * rm, c + _dir(a)[1] * rm)
             for a in (style.min_angle_deg, style.max_angle_deg)]
    truth = {"value": float(max(value, style.min_value)), "needle_angle_deg": ang,
             "pivot_xy": (c, c), "min_mark_xy": marks[0], "max_mark_xy": marks[1],
             "scale_radius_px": rm, "needle_len_px": L}
    return img, truth
