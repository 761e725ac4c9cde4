"""Work-arounds for defects of the Qt binding in use.

PySide6 6.12.0 on Python 3.11 drops references to the singletons it hands back
to C++: one reference to ``True`` per signal emission (``emit`` returns True),
and one to ``None`` per call of a Python override of a C++ virtual that returns
None (``paintEvent``, ``childEvent``, ...). They look written for Python 3.12,
where these singletons are immortal; on 3.11 the counts fall to zero after a few
hundred calls and the interpreter aborts ("Fatal Python error: bool_dealloc" or
"none_dealloc").

:func:`guard_singleton_refcounts` probes for the leak and, only if it is
present, raises the counts of ``None``, ``True`` and ``False`` by 2**40 — what
3.12 does by making them immortal. Delete this module once the binding is fixed
or Python >= 3.12 is required.
"""

from __future__ import annotations

import ctypes
import logging
import sys

from PySide6.QtCore import QObject, Signal

log = logging.getLogger(__name__)

_applied = False
_BUMP = 1 << 40


class _Probe(QObject):
    fired = Signal(object)

    def childEvent(self, event) -> None:  # noqa: N802 (Qt name)
        return None


def singleton_leaks(n: int = 64) -> dict[str, float]:
    """References lost per call: True per signal emission, None per virtual call."""
    probe = _Probe()
    probe.fired.connect(lambda _x: None)
    t0 = sys.getrefcount(True)
    for _ in range(n):
        probe.fired.emit(0)
    t1 = sys.getrefcount(True)
    n0 = sys.getrefcount(None)
    for _ in range(n):
        QObject(probe).setParent(None)  # ChildAdded/ChildRemoved -> probe.childEvent
    n1 = sys.getrefcount(None)
    return {"True": (t0 - t1) / n, "None": (n0 - n1) / (2 * n)}


def guard_singleton_refcounts() -> bool:
    """Apply the work-around when a leak is present; True when applied (once)."""
    global _applied
    if _applied:
        return True
    if sys.version_info >= (3, 12) or sys.implementation.name != "cpython":
        return False  # the singletons are immortal there
    leaks = singleton_leaks()
    if max(leaks.values()) < 0.25:
        return False
    for obj in (None, True, False):
        ctypes.c_ssize_t.from_address(id(obj)).value += _BUMP
    _applied = True
    log.warning("Qt binding leaks references to None/True (%s per call); "
                "work-around applied (see app/ui/qt_fixes.py)", leaks)
    return True
