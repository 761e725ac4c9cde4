"""Translation of the text that Qt-free code builds (alarm messages, freshness ages,
report headings), without importing Qt.

Core code calls ``translate("Context", "source text {name}")`` and formats the result;
``QT_TRANSLATE_NOOP("Context", "text")`` only marks a constant (a table label) for
extraction, and the view translates it when it shows it. Both names are the ones Qt's
``pyside6-lupdate`` looks for, so the strings land in app/i18n/*.ts with their context.

Nothing is translated until a hook is installed: the desk installs Qt's
``QCoreApplication.translate`` (app/i18n); the headless desk, the CLI and the tests of
core see the English source text.
"""

from __future__ import annotations

from collections.abc import Callable

_hook: Callable[[str, str], str] | None = None

# the desk's languages: the source text (English) and the translations in app/i18n
LANGUAGES = {"en": "English", "zh_CN": "简体中文"}


def normalise(lang: str | None) -> str | None:
    """``zh``, ``zh-CN``, ``zh_CN.UTF-8`` → ``zh_CN``; ``en_GB``, ``C`` → ``en``; None or
    another language → None."""
    if not lang:
        return None
    low = lang.replace("-", "_").split(".")[0].lower()
    if low.startswith("zh"):
        return "zh_CN"
    if low.startswith("en") or low in ("c", "posix"):
        return "en"
    return None


def check_language(text: str) -> str:
    """``--lang``'s value checked: ``zh_CN`` or ``en`` (also ``zh``, ``zh-CN``, ``en_US``);
    anything else raises ValueError naming the choices."""
    lang = normalise(text)
    if lang is None:
        raise ValueError(f"unknown language {text!r} (one of: {', '.join(LANGUAGES)})")
    return lang


def install(hook: Callable[[str, str], str] | None) -> None:
    """Translate through ``hook(context, text)`` from now on (None: the source text)."""
    global _hook
    _hook = hook


def translate(context: str, text: str) -> str:
    """``text`` in the desk's language (the source text when no hook is installed)."""
    if _hook is None:
        return text
    return _hook(context, text)


def QT_TRANSLATE_NOOP(context: str, text: str) -> str:  # noqa: N802 (Qt's marker name)
    """Mark ``text`` for extraction under ``context``; returns it unchanged."""
    return text
