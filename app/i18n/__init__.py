"""The desk's languages: English (the source text) and Simplified Chinese (zh_CN).

- ``station_patrol_zh_CN.ts`` is the translation: ``make lupdate`` gathers the source
  strings into it (``pyside6-lupdate`` over app/), ``make translations`` compiles it to
  the ``.qm`` that ships in the package (``pyside6-lrelease``); tests/i18n checks that
  the committed ``.qm`` is the compiled ``.ts`` and that every string is translated.
- The language: ``--lang`` on the command line, else the setting ``ui/language``
  (QSettings, changed in the desk's View menu), else the system locale.
- ``fonts/`` holds a subset of Noto Sans CJK SC (SIL OFL 1.1, licence beside it) with
  the glyphs of the translation, registered at start so the window and the reports
  never show boxes on a machine without a CJK font (tools/make_cjk_subset.py made it).
"""

from __future__ import annotations

import logging
from importlib import resources

from PySide6.QtCore import QCoreApplication, QLibraryInfo, QLocale, QSettings, QTranslator
from PySide6.QtGui import QFont, QFontDatabase, QGuiApplication

from app.core import i18n as core_i18n
from app.core.i18n import LANGUAGES, check_language, normalise

__all__ = ["LANGUAGES", "SETTINGS_KEY", "check_language", "choose_language", "cjk_font_family",
           "install_language", "language", "normalise", "report_font", "report_font_families",
           "start_language", "store_language"]

log = logging.getLogger(__name__)

SETTINGS_KEY = "ui/language"
CATALOGUE = "station_patrol"
FONT_FILE = "StationPatrolCJK-Regular.ttf"

_state: dict[str, object] = {"language": "en", "translators": [], "font": None}


def choose_language(cli_lang: str | None = None) -> str:
    """``--lang`` first, then the stored setting, then the system locale."""
    for lang in (cli_lang, QSettings().value(SETTINGS_KEY, None),
                 QLocale.system().name()):
        chosen = normalise(str(lang) if lang else None)
        if chosen is not None:
            return chosen
    return "en"


def store_language(lang: str) -> None:
    """Remember ``lang`` for the next start (the View menu's language choice)."""
    QSettings().setValue(SETTINGS_KEY, lang)


def language() -> str:
    """The language installed last (``en`` before any)."""
    return str(_state["language"])


def cjk_font_family() -> str | None:
    """Register the shipped CJK subset font once; its family name (None if it failed)."""
    if _state["font"] is None:
        ref = resources.files(__package__) / "fonts" / FONT_FILE
        fid = QFontDatabase.addApplicationFontFromData(ref.read_bytes())
        families = QFontDatabase.applicationFontFamilies(fid) if fid >= 0 else []
        if not families:
            log.warning("the CJK font %s could not be registered", FONT_FILE)
            _state["font"] = ""
        else:
            _state["font"] = families[0]
    return str(_state["font"]) or None


def _qt_translator(app: QCoreApplication, name: str, data: bytes | None = None,
                   folder: str | None = None) -> bool:
    t = QTranslator(app)
    if data is not None:
        t._qm = data  # noqa: SLF001 (kept alive as long as the translator)
    ok = t.load(data) if data is not None else t.load(name, folder or "")
    if ok:
        app.installTranslator(t)
        _state["translators"].append(t)
    return ok


def install_language(lang: str, app: QCoreApplication | None = None) -> str:
    """Put ``lang`` (``en`` or ``zh_CN``) in force for the running application: the
    desk's catalogue, Qt's own (standard buttons), the Qt-free core's hook and the CJK
    font as the widgets' fallback (Chinese names show in English too). Returns the
    language installed."""
    app = app or QCoreApplication.instance()
    lang = normalise(lang) or "en"
    for t in _state["translators"]:
        app.removeTranslator(t)
    _state["translators"] = []
    core_i18n.install(QCoreApplication.translate)
    if lang != "en":
        qm = resources.files(__package__) / f"{CATALOGUE}_{lang}.qm"
        if not _qt_translator(app, qm.name, data=qm.read_bytes()):
            log.warning("no translation %s; the desk stays in English", qm.name)
            lang = "en"
        else:
            qt_dir = QLibraryInfo.path(QLibraryInfo.LibraryPath.TranslationsPath)
            _qt_translator(app, f"qtbase_{lang}", folder=qt_dir)
    if isinstance(app, QGuiApplication):
        family = cjk_font_family()
        if family:
            font = app.font()
            families = [f for f in font.families() if f != family] or [font.family()]
            font.setFamilies([*families, family])
            app.setFont(font)
    _state["language"] = lang
    log.info("desk language: %s", LANGUAGES[lang])
    return lang


def start_language(app: QCoreApplication, cli_lang: str | None = None) -> str:
    """At start: name the application for QSettings (unless named already), choose the
    language (``--lang``, the setting, the system locale) and install it."""
    if not QCoreApplication.organizationName():
        QCoreApplication.setOrganizationName("Station Patrol")
    if QCoreApplication.applicationName().startswith("python") or \
            not QCoreApplication.applicationName():
        QCoreApplication.setApplicationName("station-patrol")
    return install_language(choose_language(cli_lang), app)


def report_font_families() -> list[str]:
    """Font families for a report: a sans-serif, then the CJK subset (Chinese text)."""
    family = cjk_font_family()
    return ["DejaVu Sans", "Arial", *([family] if family else []), "sans-serif"]


def report_font() -> QFont:
    font = QFont()
    font.setFamilies(report_font_families()[:-1])
    return font
