"""Find user-visible text a translated window still shows in English.

``visible_texts(widget)`` walks a widget tree: window titles, labels, buttons, group
titles, tabs, placeholders, combo items, table headers, tooltips, menus and actions.
``untranslated(text)`` names the English words left in one text: a word of Latin
letters with a lower-case letter that is not a unit, a key name or an allowed proper
noun. Codes (RTT, PG-302, OPC UA, A1) are all capitals and pass.
"""

from __future__ import annotations

import re

from PySide6.QtCore import QModelIndex, Qt
from PySide6.QtWidgets import (
    QAbstractButton,
    QComboBox,
    QGroupBox,
    QLabel,
    QLineEdit,
    QMenu,
    QTableView,
    QTabWidget,
    QTreeView,
    QWidget,
)

# units (with their SI prefixes as used on the desk), key names, proper nouns; keep small
ALLOWED = {
    # units
    "m", "mm", "cm", "km", "s", "ms", "min", "h", "rad", "deg", "px", "fps", "Hz", "kHz",
    "mps", "rps", "msg", "dB", "kPa", "MPa", "bar", "ppm", "mA", "mV", "kB", "MB",
    # key names in menus' shortcut column
    "Esc", "Ctrl", "Shift", "Alt", "Space", "Tab", "Del", "Backspace", "Enter", "Return",
    "PgUp", "PgDown", "Home", "End",
    # proper nouns and file kinds
    "Station", "Patrol",  # the product's name
    "English",  # the language menu names each language in its own words
    "Foxglove", "Lichtblick", "PlotJuggler", "Qt", "Noto", "ONNX", "Hough",
}
_WORD = re.compile(r"[A-Za-z][A-Za-z']*")
_IDENT = re.compile(r"\b\w+_\w+\b|\b\w+\.(?:toml|json|csv|pdf|html|db|onnx)\b")  # tags, files
_SHORTCUT = re.compile(r"\t.*$")


def untranslated(text: str) -> list[str]:
    """The English words in ``text`` (empty: nothing left untranslated)."""
    text = _SHORTCUT.sub("", text or "")  # "Stop\tSpace": the shortcut column
    text = re.sub(r"<[^>]+>", " ", text)  # rich text tags
    text = re.sub(r"&(?=\w)", "", text)  # mnemonics
    text = _IDENT.sub(" ", text)  # channel keys (gas_lel_pct), file names
    words = []
    for w in _WORD.findall(text):
        if w in ALLOWED or w.upper() == w or len(w) == 1:
            continue
        words.append(w)
    return words


def _actions_texts(owner: str, actions) -> list[tuple[str, str]]:
    out = []
    for a in actions:
        if a.isSeparator():
            continue
        out.append((f"{owner} action", a.text()))
        out.append((f"{owner} action tooltip", a.toolTip() if a.toolTip() != a.text()
                    .replace("&", "") else ""))
        out.append((f"{owner} action status tip", a.statusTip()))
        if a.menu() is not None:
            out.append((f"{owner} menu", a.menu().title()))
            out += _actions_texts(f"{owner} menu {a.text()!r}", a.menu().actions())
    return out


def visible_texts(root: QWidget) -> list[tuple[str, str]]:
    """``(where, text)`` for every user-visible text in ``root``'s tree."""
    out: list[tuple[str, str]] = []
    for w in [root, *root.findChildren(QWidget)]:
        where = f"{type(w).__name__} {w.objectName()!r}".strip()
        if w.isWindow():
            out.append((f"{where} window title", w.windowTitle()))
        out.append((f"{where} tooltip", w.toolTip()))
        out.append((f"{where} status tip", w.statusTip()))
        if isinstance(w, QLabel):
            out.append((f"{where} text", w.text()))
        elif isinstance(w, QAbstractButton):
            out.append((f"{where} text", w.text()))
        elif isinstance(w, QGroupBox):
            out.append((f"{where} title", w.title()))
        elif isinstance(w, QLineEdit):
            out.append((f"{where} placeholder", w.placeholderText()))
        elif isinstance(w, QComboBox):
            out += [(f"{where} item", w.itemText(i)) for i in range(w.count())]
        elif isinstance(w, QTabWidget):
            for i in range(w.count()):
                out.append((f"{where} tab", w.tabText(i)))
                out.append((f"{where} tab tooltip", w.tabToolTip(i)))
        elif isinstance(w, (QTableView, QTreeView)) and w.model() is not None:
            m = w.model()
            for orient, n in ((Qt.Orientation.Horizontal, m.columnCount(QModelIndex())),
                              (Qt.Orientation.Vertical, 0)):
                for i in range(n):
                    for role in (Qt.ItemDataRole.DisplayRole, Qt.ItemDataRole.ToolTipRole):
                        v = m.headerData(i, orient, role)
                        if isinstance(v, str):
                            out.append((f"{where} header {i}", v))
        if isinstance(w, QMenu):
            out.append((f"{where} title", w.title()))
        out += _actions_texts(where, w.actions())
    return [(where, t) for where, t in out if t]


def find_untranslated(root: QWidget) -> list[str]:
    """One line per text still in English: where it is, the text, the words."""
    seen = set()
    lines = []
    for where, text in visible_texts(root):
        words = untranslated(text)
        if words and (where, text) not in seen:
            seen.add((where, text))
            lines.append(f"{where}: {text!r} ({' '.join(words)})")
    return lines
