"""Style families of pointer gauges: many faces, fonts, bezels, ticks, zones and needles.

Qt-free: numpy + OpenCV only.  Angles are degrees clockwise from 12 o'clock on the
upright dial, as in :mod:`sim_robot.gauge_render` and the gauge profiles; a scale whose
``max_angle_deg`` is smaller than its ``min_angle_deg`` runs counter-clockwise.

* :class:`DialStyle` is one gauge's appearance and scale.
* :func:`random_style` draws a random style from a *family*; :func:`random_value` a value
  to show.  :func:`sim_robot.gauge_dial.draw_dial` draws the upright dial and returns its
  ground truth; :mod:`sim_robot.gauge_scene` puts the dial into camera frames.

Families.  The tuning families, which readers may be developed and tuned on:

* ``plant``   white or cream faces, dark ink, line ticks, thin/arrow/lance needles, brand
  text, optional colour zones;
* ``dark``    black or dark faces with white ink, white/yellow/orange needles, chrome bezels;
* ``colour``  blue, green, yellow, grey or printed-texture faces, dot or line ticks, zones;
* ``process`` what real process gauges carry: two-ended needles with a counterweight,
  arrow tails wider than the thin tip, a red set-point pointer, a stop pin with the needle
  resting on it, counter-clockwise and 270-320 deg scales, compound ranges, a second scale.

* ``heritage`` parchment faces with a printed mottled texture, Hershey script fonts,
  numerals outside a double printed arc, wedge major ticks with dot minor ticks between the
  two arcs, a spade-headed needle with a ring counterweight, brass bezels with screws (it
  was the held-out family until readers had been looked at on it; now it is tuned on).
* ``marine``  two-tone faces (a pale upper half over a tinted lower band) in lavender, mint
  or peach, seven-segment numerals drawn as strokes, diamond major ticks with square minor
  ticks on a tinted band, a baton needle with a square counterweight, a hexagonal flange
  bezel painted olive, navy or maroon, ink in deep green or plum, and its own backdrops
  (tiled walls and control panels).  The second held-out family; tuned on since readers
  were looked at on it.

* ``nordic``  sunburst faces (fine radial rays, brighter at the centre) in slate, pine or ice,
dot-matrix numerals (5 x 7 dots, no Hershey font, no strokes), hollow ring major ticks with
short tangential dash minor ticks, a "rail" scale (two fine arcs with every other major
interval filled), a sword needle (a blade widening to mid-length, a cross-guard and a
pommel disc on the tail), knurled bezels in graphite, bronze or copper, ink in frost,
amber or indigo, a bars logo, and its own backdrops (brick walls and corrugated cladding).
  The third held-out family; tuned on since it was measured twice and looked at.

``atlas`` (:mod:`sim_robot.gauge_atlas`) was the held-out family until readers were
measured on it and its figures looked at: powder-coated or carbon-weave faces, block
numerals, tee and spike ticks on a segmented arc, rim zones, dart / crescent / paddle
needles on a hex nut, a flag set-point, bayonet bezels, rack and grating backdrops.  It is
kept out of the tuning families (so that last round's figures can be re-run,
``bench/meter_bench.py --heldout atlas``) but no longer counts as unseen.

The held-out family, ``foundry`` (:mod:`sim_robot.gauge_foundry`, its own renderer), is
kept out of all tuning (it is the benchmark's test split): printed paper faces (yellowed,
grainy, unevenly lit, the bezel's shadow on them) or satin aluminium, its own typeface,
units such as "kgf/cm²", EN 837 class marks, dual scales with an inner red second scale,
keystone and sliver ticks, a hairline arc or a mirror band, inlaid zones, lancet, lozenge
and spear needles with a shadow on a domed hub, a drag pointer on the glass, polished
and crimped bezels mirroring the room, glass reflections, glycerine fill with a meniscus
and bubbles, 270 / 240-300 / 90 deg scales, counter-clockwise vacuum gauges, the needle
resting against a stop pin, and its own backdrops (process skids, out-of-focus plant).
None of these elements appears in another family.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .gauge_atlas import ATLAS, ATLAS_NEEDLES, ATLAS_NORMAL, BLOCK_FONT, atlas_params
from .gauge_foundry import FOUNDRY, FOUNDRY_NORMAL, FOUNDRY_TWO_ENDED, foundry_params

__all__ = [
    "FAMILIES",
    "HELD_OUT_FAMILY",
    "HELD_OUT_CHOICES",
    "NEVER_TRAINED",
    "TUNING_FAMILIES",
    "BLOCK_FONT",
    "DialStyle",
    "random_style",
    "random_value",
]

TUNING_FAMILIES: tuple[str, ...] = ("plant", "dark", "colour", "process", "heritage", "marine",
                                     "nordic")
HELD_OUT_FAMILY = FOUNDRY  # the bench's test split
# the bench's held-out family and the former ones it can still be run on (--heldout)
HELD_OUT_CHOICES: tuple[str, ...] = (HELD_OUT_FAMILY, ATLAS)
NEVER_TRAINED = HELD_OUT_CHOICES  # families no training may draw
FAMILIES: tuple[str, ...] = (*TUNING_FAMILIES, ATLAS, FOUNDRY)

RED = (40, 40, 210)
GREEN = (60, 170, 60)
YELLOW = (40, 200, 235)
TWO_ENDED = ("two-ended", "arrow-tail", "spade", "baton", "sword", *ATLAS_NEEDLES,
             *FOUNDRY_TWO_ENDED)
NORMAL_ZONE_BGR = (GREEN, ATLAS_NORMAL, FOUNDRY_NORMAL)  # the colours of a normal-range zone
SEGMENT_FONT = -1  # seven-segment numerals drawn as strokes (:mod:`.gauge_dial`)
DOT_FONT = -2  # dot-matrix numerals, 5 x 7 dots (:mod:`.gauge_dial`)


@dataclass(frozen=True)
class DialStyle:
    """One gauge face.  Lengths are fractions of the square crop's side."""

    family: str = "plant"
    name: str = "gauge"
    unit: str = "bar"
    min_value: float = 0.0
    max_value: float = 10.0
    min_angle_deg: float = -135.0
    max_angle_deg: float = 135.0
    major_step: float = 1.0
    minor_per_major: int = 5
    medium_ticks: bool = False  # a medium tick half-way between majors
    label_every: int = 1
    # face
    face_kind: str = "white"  # white | cream | black | colour | texture | parchment | two-tone
    # | sunburst | powder | carbon | paper | satin
    face_bgr: tuple[int, int, int] = (240, 242, 244)
    face_low_bgr: tuple[int, int, int] | None = None  # lower band of a two-tone face
    ink_bgr: tuple[int, int, int] = (25, 25, 25)
    face_radius: float = 0.45
    texture_seed: int = 0
    # text
    font: int = cv2.FONT_HERSHEY_SIMPLEX  # or SEGMENT_FONT, DOT_FONT, BLOCK_FONT
    numeral_orient: str = "upright"  # upright | radial (turned along the radius)
    italic: bool = False
    text_h: float = 0.045  # numeral height
    text_weight: float = 0.006
    numerals: str = "inside"  # inside | outside | none
    brand: str = ""
    logo: str = "none"  # none | circle | diamond | triangle | star | bars | fan
    face_print: str = "none"  # none | plate (a maker's plate and a bar code)
    second_scale: float | None = None  # factor of an inner red second scale (e.g. psi)
    second_unit: str = ""  # its unit, where the dial prints it (foundry)
    # bezel
    bezel_kind: str = "thin"  # none | thin | thick | chrome | screws | brass | hex | knurled
    # | bayonet
    bezel_bgr: tuple[int, int, int] = (40, 40, 40)
    # ticks
    scale_radius: float = 0.38
    tick_len: float = 0.05
    tick_width: float = 0.007
    major_kind: str = "line"  # line | wedge | dot | diamond | ring | tee
    minor_kind: str = "line"  # line | dot | square | tangent | spike
    arc: str = "none"  # none | inside | outside | crossing | double | band | rail | segmented
    zones: tuple[tuple[float, float, tuple[int, int, int]], ...] = ()
    zone_kind: str = "arc"  # arc (on the ticks) | rim (sectors outside the ticks)
    # needle
    needle_shape: str = "thin"  # thin | arrow | lance | two-ended | arrow-tail | spade | baton
    # | sword | dart | crescent | paddle
    needle_bgr: tuple[int, int, int] = (20, 20, 20)
    needle_len: float = 0.37
    needle_width: float = 0.022
    tail_len: float = 0.06
    hub_radius: float = 0.045
    hub_bgr: tuple[int, int, int] = (20, 20, 20)
    hub_kind: str = "disc"  # disc | nut
    setpoint: float | None = None  # value of a red set-point pointer
    setpoint_kind: str = "lance"  # lance | flag
    stop_pin: bool = False
    pin_offset_deg: float = 7.0  # the stop pin's angle below the minimum mark
    rest_at_max: bool = False  # the needle rests at the maximum (a vacuum gauge's zero)
    fill: str = "dry"  # dry | glycerine (foundry)
    band_bgr: tuple[int, int, int] | None = None  # the tinted band of arc "band"

    @property
    def direction(self) -> int:
        return 1 if self.max_angle_deg > self.min_angle_deg else -1

    def angle_of(self, value: float) -> float:
        f = (value - self.min_value) / (self.max_value - self.min_value)
        return self.min_angle_deg + f * (self.max_angle_deg - self.min_angle_deg)

    @property
    def pin_angle_deg(self) -> float:
        """Where the stop pin sits: just below the minimum mark (beyond the maximum mark
        when the needle rests at the maximum)."""
        if self.rest_at_max:
            return self.max_angle_deg + self.direction * self.pin_offset_deg
        return self.min_angle_deg - self.direction * self.pin_offset_deg

    @property
    def rest_value(self) -> float:
        """The value a needle resting on the stop pin shows."""
        return self.max_value if self.rest_at_max else self.min_value

    def tick_list(self) -> list[tuple[float, float, str]]:
        """(value, angle, "major" | "medium" | "minor") for every tick."""
        n_major = round((self.max_value - self.min_value) / self.major_step)
        n = n_major * self.minor_per_major
        out = []
        for i in range(n + 1):
            v = self.min_value + i * self.major_step / self.minor_per_major
            k = i % self.minor_per_major
            kind = ("major" if k == 0 else
                    "medium" if self.medium_ticks and 2 * k == self.minor_per_major else "minor")
            out.append((v, self.angle_of(v), kind))
        return out

    def tick_span(self) -> tuple[float, float]:
        """Inner and outer radius of the major ticks (fractions of the crop side)."""
        r, ln = self.scale_radius, self.tick_len
        if self.arc == "outside":
            return r, r + ln
        if self.arc == "crossing":
            return r - ln / 2, r + ln / 2
        return r - ln, r  # none, inside, double, rail (ticks between the two arcs)

    def profile(self) -> dict:
        """The angle-form gauge profile a user would write for this face."""
        p = {"name": self.name, "unit": self.unit, "min_value": self.min_value,
             "max_value": self.max_value, "min_angle_deg": round(self.min_angle_deg, 3),
             "max_angle_deg": round(self.max_angle_deg, 3)}
        green = [z for z in self.zones if z[2] in NORMAL_ZONE_BGR]
        if green:
            p["normal_min"], p["normal_max"] = green[0][0], green[0][1]
        if self.needle_shape in TWO_ENDED:
            p["needle"] = "two-ended"
        if self.setpoint is not None:
            p["ignore_colour"] = "red"
        return p


# ----------------------------------------------------------------------------- random styles

_RANGES = (  # (min, max, unit, major step, minors per major)
    (0.0, 1.6, "MPa", 0.2, 4), (0.0, 2.5, "MPa", 0.5, 5), (0.0, 4.0, "MPa", 0.5, 5),
    (0.0, 10.0, "bar", 1.0, 5), (0.0, 16.0, "bar", 2.0, 4), (0.0, 25.0, "bar", 5.0, 5),
    (0.0, 160.0, "psi", 20.0, 4), (0.0, 300.0, "psi", 50.0, 5), (0.0, 600.0, "kPa", 100.0, 5),
    (4.0, 20.0, "mA", 2.0, 4), (20.0, 120.0, "degC", 20.0, 4), (50.0, 250.0, "psi", 25.0, 5),
)
_COMPOUND = ((-0.1, 0.9, "MPa", 0.1, 5), (-1.0, 3.0, "bar", 0.5, 5), (-1.0, 5.0, "bar", 1.0, 5),
             (-30.0, 60.0, "psi", 10.0, 5))
_BRANDS = ("NORDTEC", "PRESSCO", "KAELO", "VALMET-X", "DURAGAUGE", "TECHNIK", "OSTRA",
           "ACME", "HYDRA", "SIGMA")
_TUNING_FONTS = (cv2.FONT_HERSHEY_SIMPLEX, cv2.FONT_HERSHEY_PLAIN, cv2.FONT_HERSHEY_DUPLEX,
                 cv2.FONT_HERSHEY_COMPLEX, cv2.FONT_HERSHEY_TRIPLEX,
                 cv2.FONT_HERSHEY_COMPLEX_SMALL)
_HUBS = ((20, 20, 20), (150, 150, 155), (200, 200, 205), RED, (120, 60, 30))
_HERITAGE_FONTS = (cv2.FONT_HERSHEY_SCRIPT_SIMPLEX, cv2.FONT_HERSHEY_SCRIPT_COMPLEX)


def _pick(rng: np.random.Generator, seq):
    return seq[int(rng.integers(0, len(seq)))]


def _col(rng, lo, hi) -> tuple[int, int, int]:
    return tuple(int(v) for v in rng.integers(lo, hi, 3))


def _span(rng, lo=90.0, hi=320.0, common=(180.0, 240.0, 270.0)) -> float:
    return float(_pick(rng, common)) if rng.random() < 0.6 else float(rng.uniform(lo, hi))


def _zones(rng, lo, hi) -> tuple:
    fs = hi - lo
    a, b = sorted(rng.uniform(0.1, 0.9, 2))
    b = max(b, a + 0.2)
    zs = [(lo + a * fs, lo + min(b, 0.92) * fs, GREEN)]
    if rng.random() < 0.7:
        zs.append((lo + min(b, 0.92) * fs, lo + min(b + 0.1, 0.96) * fs, YELLOW))
        zs.append((lo + min(b + 0.1, 0.96) * fs, hi, RED))
    return tuple(zs)


def random_style(family: str, rng: np.random.Generator, *,
                 value_range: tuple[float, float, str] | None = None,
                 name: str | None = None) -> DialStyle:
    """A random style of ``family``; ``value_range`` (min, max, unit) fixes the scale."""
    if family not in FAMILIES:
        raise ValueError(f"unknown gauge style family {family!r}; one of {', '.join(FAMILIES)}")
    wide = ("process", "heritage", "marine", "nordic")  # compound ranges, spans to 320 deg
    compound = family in wide and rng.random() < 0.3
    lo, hi, unit, step, minors = _pick(rng, _COMPOUND if compound else _RANGES)
    if value_range is not None:
        lo, hi, unit = value_range
        step = _nice_step((hi - lo) / 8)
        minors = 5 if round((hi - lo) / step) <= 10 else 4
    span = _span(rng) if family in wide else _span(rng, 120, 280)
    centre = 0.0 if rng.random() < 0.8 or span > 200 else float(rng.uniform(-30, 30))
    ccw = rng.random() < {"process": 0.3, "heritage": 0.15, "marine": 0.15,
                          "nordic": 0.2}.get(family, 0.05)
    a0, a1 = centre - span / 2, centre + span / 2
    if ccw:
        a0, a1 = a1, a0
    n_major = round((hi - lo) / step)
    d: dict = {"family": family, "name": name or f"{family}_{lo:g}_{hi:g}{unit}",
               "unit": unit, "min_value": float(lo), "max_value": float(hi),
               "min_angle_deg": a0, "max_angle_deg": a1, "major_step": float(step),
               "minor_per_major": int(minors),
               "medium_ticks": minors % 2 == 0 and rng.random() < 0.5,
               "label_every": 2 if n_major > 8 and rng.random() < 0.5 else 1,
               "texture_seed": int(rng.integers(0, 1 << 30)),
               "text_h": float(rng.uniform(0.035, 0.06)),
               "text_weight": float(rng.uniform(0.004, 0.009)),
               "tick_len": float(rng.uniform(0.035, 0.07)),
               "tick_width": float(rng.uniform(0.005, 0.011)),
               "needle_len": float(rng.uniform(0.33, 0.40)),
               "needle_width": float(rng.uniform(0.016, 0.03)),
               "hub_radius": float(rng.uniform(0.03, 0.07)),
               "italic": bool(rng.random() < 0.25),
               "brand": _pick(rng, _BRANDS) if rng.random() < 0.6 else "",
               "logo": _pick(rng, ("none", "circle", "diamond", "triangle"))}
    if family == "heritage":
        d.update(_heritage(rng, d))
    elif family == "marine":
        d.update(_marine(rng, d))
    elif family == "nordic":
        d.update(_nordic(rng, d))
    elif family == ATLAS:
        d.update(atlas_params(rng, d, value_range is not None))
    elif family == FOUNDRY:
        d.update(foundry_params(rng, d, value_range is not None))
    else:
        d.update(_tuning(family, rng, d))
    if rng.random() < 0.35 and "zones" not in d:
        d["zones"] = _zones(rng, lo, hi)
    return DialStyle(**d)


def _nice_step(raw: float) -> float:
    e = 10 ** math.floor(math.log10(raw))
    for m in (1, 2, 2.5, 5, 10):
        if m * e >= raw:
            return m * e
    return 10 * e


def _tuning(family: str, rng, d: dict) -> dict:
    out = {"font": _pick(rng, _TUNING_FONTS), "numerals": "inside" if rng.random() < 0.8
           else _pick(rng, ("outside", "none")),
           "bezel_kind": _pick(rng, ("none", "thin", "thick", "chrome", "screws")),
           "arc": _pick(rng, ("none", "none", "inside", "outside", "crossing")),
           "major_kind": "line", "minor_kind": "line"}
    dark_ink = (20, 20, 20)
    if family == "plant":
        out.update(face_kind=_pick(rng, ("white", "cream")),
                   needle_shape=_pick(rng, ("thin", "arrow", "lance")),
                   needle_bgr=_pick(rng, ((20, 20, 20), (30, 30, 30), RED)),
                   bezel_bgr=_col(rng, 20, 70) if rng.random() < 0.5 else _col(rng, 140, 190))
        out["face_bgr"] = (244, 246, 247) if out["face_kind"] == "white" else (205, 232, 244)
        out["ink_bgr"] = dark_ink
    elif family == "dark":
        out.update(face_kind="black", face_bgr=_col(rng, 15, 45), ink_bgr=(235, 235, 235),
                   needle_shape=_pick(rng, ("thin", "arrow", "lance")),
                   needle_bgr=_pick(rng, ((240, 240, 240), (30, 200, 240), (30, 130, 245))),
                   bezel_kind=_pick(rng, ("chrome", "thick", "thin")), bezel_bgr=(160, 160, 165),
                   major_kind=_pick(rng, ("line", "wedge")))
    elif family == "colour":
        kind = _pick(rng, ("colour", "colour", "texture"))
        face = _pick(rng, ((190, 120, 40), (120, 190, 120), (90, 220, 245), (200, 200, 195),
                           (150, 200, 240))) if kind == "colour" else _col(rng, 170, 215)
        out.update(face_kind=kind, face_bgr=face, ink_bgr=dark_ink,
                   needle_shape=_pick(rng, ("lance", "arrow", "thin")),
                   needle_bgr=_pick(rng, ((20, 20, 20), (20, 20, 120), (90, 30, 20))),
                   bezel_bgr=_col(rng, 30, 200), major_kind=_pick(rng, ("line", "dot", "wedge")),
                   minor_kind=_pick(rng, ("line", "dot")))
    else:  # process
        out.update(face_kind=_pick(rng, ("white", "white", "cream")), ink_bgr=dark_ink,
                   needle_shape=_pick(rng, ("two-ended", "arrow-tail", "thin", "arrow")),
                   needle_bgr=_pick(rng, ((20, 20, 20), (25, 25, 25), RED)),
                   bezel_kind=_pick(rng, ("screws", "chrome", "thick")),
                   bezel_bgr=_col(rng, 120, 190), stop_pin=bool(rng.random() < 0.6),
                   second_scale=14.5 if d["unit"] == "bar" and rng.random() < 0.5 else None)
        out["face_bgr"] = (244, 246, 247) if out["face_kind"] == "white" else (205, 232, 244)
        out["tail_len"] = float(rng.uniform(0.08, 0.14))
        if rng.random() < 0.4:
            out["needle_bgr"] = (20, 20, 20)
            out["setpoint"] = _setpoint(rng, d)
    if out["numerals"] == "outside":
        out["scale_radius"] = float(rng.uniform(0.30, 0.33))
    else:
        out["scale_radius"] = float(rng.uniform(0.35, 0.41))
    out.setdefault("tail_len", float(rng.uniform(0.0, 0.08)))
    out["hub_bgr"] = out["needle_bgr"] if rng.random() < 0.6 else _pick(rng, _HUBS)
    if out["face_kind"] == "black" or out["bezel_kind"] == "none":
        out["face_radius"] = 0.47 if out["bezel_kind"] != "none" else 0.49
    return out


def _setpoint(rng, d) -> float:
    return float(d["min_value"] + rng.uniform(0.1, 0.9) * (d["max_value"] - d["min_value"]))


def _heritage(rng, d: dict) -> dict:
    face = (int(rng.integers(150, 185)), int(rng.integers(200, 225)), int(rng.integers(225, 245)))
    return {"face_kind": "parchment", "face_bgr": face,
            "ink_bgr": (int(rng.integers(20, 50)), int(rng.integers(30, 55)),
                        int(rng.integers(50, 80))),
            "font": _pick(rng, _HERITAGE_FONTS), "numerals": "outside",
            "scale_radius": float(rng.uniform(0.29, 0.32)), "arc": "double",
            "major_kind": "wedge", "minor_kind": "dot", "bezel_kind": "brass",
            "bezel_bgr": (60, 150, 190), "needle_shape": "spade",
            "needle_bgr": _pick(rng, ((90, 40, 20), (30, 30, 30), (110, 70, 30))),
            "hub_bgr": (60, 140, 180), "tail_len": float(rng.uniform(0.09, 0.13)),
            "stop_pin": bool(rng.random() < 0.5), "face_radius": 0.44,
            "setpoint": _setpoint(rng, d) if rng.random() < 0.25 else None}


_MARINE_FACES = (  # (upper half, lower band): lavender, mint, peach
    ((246, 232, 240), (225, 190, 215)), ((232, 246, 234), (185, 225, 190)),
    ((226, 236, 250), (170, 200, 245)))
_MARINE_INKS = ((40, 90, 20), (90, 20, 80))  # deep green, plum
_MARINE_BEZELS = ((60, 105, 100), (90, 40, 20), (40, 30, 110))  # olive, navy, maroon
_MARINE_NEEDLES = ((150, 30, 140), (20, 110, 60), (120, 60, 0))  # magenta, green, teal


def _marine(rng, d: dict) -> dict:
    upper, lower = _pick(rng, _MARINE_FACES)
    ink = _pick(rng, _MARINE_INKS)
    needle = _pick(rng, _MARINE_NEEDLES)
    return {"face_kind": "two-tone", "face_bgr": upper, "face_low_bgr": lower, "ink_bgr": ink,
            "font": SEGMENT_FONT, "italic": False,
            "numerals": "inside" if rng.random() < 0.7 else "none",
            "scale_radius": float(rng.uniform(0.33, 0.37)), "arc": "band",
            "band_bgr": tuple(int(0.85 * v) for v in upper),
            "major_kind": "diamond", "minor_kind": "square", "bezel_kind": "hex",
            "bezel_bgr": _pick(rng, _MARINE_BEZELS), "needle_shape": "baton",
            "needle_bgr": needle, "hub_bgr": needle, "logo": "star",
            "brand": _pick(rng, ("SEAWAY", "KEEL", "HARBOR")) if rng.random() < 0.6 else "",
            "tail_len": float(rng.uniform(0.07, 0.12)), "face_radius": 0.40,
            "needle_len": float(rng.uniform(0.30, 0.35)),
            "stop_pin": bool(rng.random() < 0.4),
            "setpoint": _setpoint(rng, d) if rng.random() < 0.2 else None}


_NORDIC_DARK = ((95, 80, 64), (58, 84, 46))  # slate, pine: light ink on them
_NORDIC_LIGHT = ((250, 240, 226),)  # ice: dark ink
_NORDIC_LIGHT_INKS = ((125, 48, 42),)  # indigo
_NORDIC_DARK_INKS = ((246, 236, 200), (72, 196, 252))  # frost, amber
_NORDIC_BEZELS = ((18, 20, 24), (40, 105, 205), (30, 80, 216))  # graphite, bronze, copper
_NORDIC_NEEDLES_DARK = ((12, 64, 244), (250, 252, 238))  # vermilion, ice white
_NORDIC_NEEDLES_LIGHT = ((12, 64, 244), (72, 24, 8))  # vermilion, midnight


def _nordic(rng, d: dict) -> dict:
    dark = rng.random() < 0.55
    face = _pick(rng, _NORDIC_DARK if dark else _NORDIC_LIGHT)
    ink = _pick(rng, _NORDIC_DARK_INKS if dark else _NORDIC_LIGHT_INKS)
    needle = _pick(rng, _NORDIC_NEEDLES_DARK if dark else _NORDIC_NEEDLES_LIGHT)
    inside = rng.random() < 0.75
    out = {"face_kind": "sunburst", "face_bgr": face, "ink_bgr": ink, "font": DOT_FONT,
           "italic": False, "numerals": "inside" if inside else "outside",
           "scale_radius": float(rng.uniform(0.34, 0.39) if inside else rng.uniform(0.29, 0.31)),
           "arc": "rail",
           "major_kind": "ring", "minor_kind": "tangent", "bezel_kind": "knurled",
           "bezel_bgr": _pick(rng, _NORDIC_BEZELS), "needle_shape": "sword",
           "needle_bgr": needle, "hub_bgr": (128, 132, 140), "logo": "bars",
           "brand": _pick(rng, ("FJORD", "POLARIS", "BIRKA")) if rng.random() < 0.6 else "",
           "tail_len": float(rng.uniform(0.06, 0.11)), "face_radius": 0.43,
           "needle_len": float(rng.uniform(0.31, 0.37)),
           "stop_pin": bool(rng.random() < 0.4),
           "setpoint": _setpoint(rng, d) if rng.random() < 0.2 else None}
    if out["setpoint"] is not None and _reddish(needle):
        # the profile then says to ignore red (the set-point pointer's colour): the needle
        # takes the print's colour instead of one the reader is told is not the needle's
        out["needle_bgr"] = ink
    return out


def _reddish(bgr) -> bool:
    """Whether a colour is of the hues a profile's ``"ignore_colour": "red"`` covers."""
    b, g, r = (int(v) for v in bgr)
    return r > 150 and r > 1.6 * max(b, g)


def random_value(style: DialStyle, rng: np.random.Generator,
                 p_rest: float | None = None) -> float:
    """A value to show; with ``p_rest`` (and a stop pin) the needle rests on the pin.

    ``p_rest`` defaults to 0.08, and to 0.35 for ``atlas`` and ``foundry`` (real plant gauges
    often stand at zero).  A needle on the pin shows its rest value (the minimum, or a vacuum
    gauge's zero at the maximum): the returned value is then ``style.rest_value`` and
    :func:`draw_dial` draws it against the pin.
    """
    if p_rest is None:
        p_rest = 0.35 if style.family in (ATLAS, FOUNDRY) else 0.08
    if style.stop_pin and rng.random() < p_rest:
        return float(style.rest_value)
    return float(rng.uniform(style.min_value, style.max_value))
