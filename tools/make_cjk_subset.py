"""Make the small CJK font the desk ships (app/i18n/fonts/StationPatrolCJK-Regular.ttf).

A subset of Noto Sans CJK SC Regular (SIL Open Font Licence 1.1) holding the glyphs of
the zh_CN translation, ASCII and common CJK punctuation, with its outlines turned from
CFF into TrueType quadratics (Qt's PDF writer embeds TrueType outlines as a font, so a
report's Chinese text stays text). Renamed "Station Patrol CJK": the licence keeps the
reserved names ("Source", "Noto") for the original fonts.

Run again after the translation gains new characters (tests/i18n fails until then)::

    python3 -m venv /tmp/ft && /tmp/ft/bin/pip install fonttools
    /tmp/ft/bin/python tools/make_cjk_subset.py \
        /usr/share/fonts/opentype/noto/NotoSansCJK-Regular.ttc

(Debian's fonts-noto-cjk package; the .otf of Noto Sans CJK SC works too.) fonttools is
needed only here, never to run the desk.
"""

from __future__ import annotations

import argparse
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

from fontTools import subset
from fontTools.pens.cu2quPen import Cu2QuPen
from fontTools.pens.ttGlyphPen import TTGlyphPen
from fontTools.ttLib import TTCollection, TTFont, newTable

ROOT = Path(__file__).resolve().parent.parent
TS = ROOT / "app/i18n/station_patrol_zh_CN.ts"
OUT = ROOT / "app/i18n/fonts/StationPatrolCJK-Regular.ttf"
FAMILY = "Station Patrol CJK"
PUNCTUATION = "，。：；！？（）【】《》〈〉、“”‘’—…·°℃±×÷→←↑↓％‰～·「」『』"


def characters(ts: Path) -> set[str]:
    chars = {chr(c) for c in range(0x20, 0x7F)} | set(PUNCTUATION)
    for tr in ET.parse(ts).getroot().iter("translation"):
        chars |= set(tr.text or "")
        for form in tr.iter("numerusform"):
            chars |= set(form.text or "")
    return {c for c in chars if c.isprintable()}


def open_source(path: Path) -> TTFont:
    if path.suffix.lower() == ".ttc":
        for font in TTCollection(str(path)).fonts:
            if font["name"].getDebugName(1) == "Noto Sans CJK SC":
                return font
        raise SystemExit(f"{path}: no Noto Sans CJK SC in this collection")
    return TTFont(str(path))


def to_truetype(font: TTFont) -> None:
    """CFF outlines → glyf (cubic → quadratic, 1 unit tolerance); fontTools' otf2ttf."""
    order = font.getGlyphOrder()
    glyphs = font.getGlyphSet()
    glyf = newTable("glyf")
    glyf.glyphOrder = order
    glyf.glyphs = {}
    for name in order:
        pen = TTGlyphPen(glyphs)
        glyphs[name].draw(Cu2QuPen(pen, max_err=1.0, reverse_direction=True))
        glyf[name] = pen.glyph()
    font["glyf"] = glyf
    font["loca"] = newTable("loca")
    for tag in ("CFF ", "VORG"):
        if tag in font:
            del font[tag]
    maxp = font["maxp"]
    maxp.tableVersion = 0x00010000
    for field in ("maxZones", "maxTwilightPoints", "maxStorage", "maxFunctionDefs",
                  "maxInstructionDefs", "maxStackElements", "maxSizeOfInstructions",
                  "maxComponentElements"):
        setattr(maxp, field, 0)
    maxp.maxZones = 1
    font["head"].glyphDataFormat = 0
    post = font["post"]
    post.formatType = 2.0
    post.extraNames = []
    post.mapping = {}
    post.glyphOrder = order
    font.sfntVersion = "\x00\x01\x00\x00"


def rename(font: TTFont) -> None:
    name = font["name"]
    for rec in list(name.names):
        if rec.nameID in (1, 3, 4, 6, 16, 17, 21, 22):
            name.removeNames(nameID=rec.nameID)
    name.setName(FAMILY, 1, 3, 1, 0x409)
    name.setName("Regular", 2, 3, 1, 0x409)
    name.setName(f"{FAMILY} Regular; subset of Noto Sans CJK SC", 3, 3, 1, 0x409)
    name.setName(f"{FAMILY} Regular", 4, 3, 1, 0x409)
    name.setName("StationPatrolCJK-Regular", 6, 3, 1, 0x409)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("source", type=Path, help="NotoSansCJK-Regular.ttc or NotoSansCJKsc-Regular.otf")
    p.add_argument("--ts", type=Path, default=TS)
    p.add_argument("--out", type=Path, default=OUT)
    args = p.parse_args(argv)
    font = open_source(args.source)
    chars = characters(args.ts)
    opts = subset.Options()
    opts.layout_features = ["kern", "vert"]
    opts.name_IDs = ["*"]
    opts.notdef_outline = True
    opts.hinting = False
    sub = subset.Subsetter(opts)
    sub.populate(unicodes=[ord(c) for c in chars])
    sub.subset(font)
    to_truetype(font)
    rename(font)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    font.save(str(args.out))
    missing = sorted(c for c in chars if ord(c) not in font.getBestCmap())
    print(f"{args.out}: {len(chars)} characters asked, {len(font.getGlyphOrder())} glyphs, "
          f"{args.out.stat().st_size} bytes; not in the source font: {''.join(missing)!r}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
