"""The zh_CN catalogue: the shipped .qm is the compiled .ts, the .ts holds every string
of the source with a translation, placeholders survive, and the shipped CJK font has a
glyph for every character of the translation."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
I18N = ROOT / "app" / "i18n"
TS = I18N / "station_patrol_zh_CN.ts"
QM = I18N / "station_patrol_zh_CN.qm"


def _tool(name: str, *args: str) -> subprocess.CompletedProcess:
    """A PySide6 tool (pyside6-lupdate, pyside6-lrelease) of this interpreter's PySide6."""
    code = (f"import sys; from PySide6.scripts.pyside_tool import {name}; "
            f"sys.argv[0] = 'pyside6-{name}'; {name}()")
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True,
                          text=True, timeout=120, cwd=ROOT)


def _messages(ts: Path) -> dict[tuple[str, str], ET.Element]:
    out = {}
    for ctx in ET.parse(ts).getroot().iter("context"):
        name = ctx.findtext("name") or ""
        for msg in ctx.iter("message"):
            out[(name, msg.findtext("source") or "")] = msg.find("translation")
    return out


def test_shipped_qm_is_the_compiled_ts(tmp_path):
    out = tmp_path / "fresh.qm"
    r = _tool("lrelease", "-silent", str(TS), "-qm", str(out))
    assert r.returncode == 0, r.stderr
    assert out.read_bytes() == QM.read_bytes(), "app/i18n/*.qm is stale: make translations"


def test_ts_has_every_source_string_translated(tmp_path):
    fresh = tmp_path / "fresh.ts"
    shutil.copy(TS, fresh)
    r = _tool("lupdate", "-extensions", "py", "-locations", "none", "-no-obsolete",
              "-target-language", "zh_CN", "app", "-ts", str(fresh))
    assert r.returncode == 0, r.stderr
    now, shipped = _messages(fresh), _messages(TS)
    new = sorted(set(now) - set(shipped))
    assert not new, f"{len(new)} strings not in the .ts (make lupdate, translate): {new[:20]}"
    untranslated = [k for k, tr in shipped.items()
                    if tr.get("type") in ("unfinished", "vanished", "obsolete") or not tr.text]
    assert not untranslated, f"{len(untranslated)} without a translation: {untranslated[:20]}"


def test_translations_keep_placeholders_and_shortcut_columns():
    for (ctx, src), tr in _messages(TS).items():
        text = tr.text or ""
        assert sorted(re.findall(r"\{\w*\}", src)) == sorted(re.findall(r"\{\w*\}", text)), \
            (ctx, src, text)
        assert src.count("\t") == text.count("\t"), (ctx, src, text)
        if "\t" in src:  # the shortcut column is the key itself
            assert src.split("\t")[1] == text.split("\t")[1], (ctx, src, text)


def test_shipped_font_has_every_character_of_the_translation(qapp):
    from importlib import resources

    from PySide6.QtGui import QRawFont

    from app.i18n import FONT_FILE

    data = (resources.files("app.i18n") / "fonts" / FONT_FILE).read_bytes()
    font = QRawFont(data, 12.0)
    assert font.isValid()
    chars = {c for tr in _messages(TS).values() for c in (tr.text or "") if c.isprintable()}
    missing = sorted(c for c in chars if not font.supportsCharacter(ord(c)))
    assert not missing, f"run tools/make_cjk_subset.py: no glyph for {''.join(missing)!r}"
    assert (I18N / "fonts" / "OFL.txt").read_text().startswith(FONT_FILE)


@pytest.mark.parametrize("given, lang", [("zh_CN", "zh_CN"), ("zh", "zh_CN"),
                                         ("zh-CN.UTF-8", "zh_CN"), ("en", "en"),
                                         ("en_GB", "en"), ("C", "en"), ("de_DE", None),
                                         ("", None), (None, None)])
def test_language_names_are_normalised(given, lang):
    from app.core.i18n import normalise

    assert normalise(given) == lang


def test_an_unknown_language_is_refused_with_the_choices():
    from app.cli import build_parser

    with pytest.raises(SystemExit) as e:
        build_parser().parse_args(["--demo", "--lang", "klingon"])
    assert e.value.code == 2
    assert build_parser().parse_args(["--demo", "--lang", "zh"]).lang == "zh_CN"
