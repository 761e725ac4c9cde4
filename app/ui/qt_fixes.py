"""Work-arounds for defects of the Qt binding in use.

PySide6 6.12.0 on Python 3.11 loses one reference to ``True`` on every signal
emission (with or without a slot connected). ``True`` is not immortal before
Python 3.12, so after a few hundred emissions its count reaches zero and the
interpreter aborts with "Fatal Python error: bool_dealloc". :func:`guard_true_refcount`
detects the leak with a probe and, only if it is present, raises the count of
``True`` so far that the leak can never bring it to zero (2**40 emissions).
Remove this module once the binding is fixed or Python >= 3.12 is required.
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


def true_leak_per_emit(n: int = 64) -> float:
    """References to True lost per signal emission (0 on a sound binding)."""
    probe = _Probe()
    probe.fired.connect(lambda _x: None)
    before = sys.getrefcount(True)
    for _ in range(n):
        probe.fired.emit(0)
    return (before - sys.getrefcount(True)) / n


def guard_true_refcount() -> bool:
    """Apply the work-around when the leak is present; True when applied (once)."""
    global _applied
    if _applied:
        return True
    if sys.version_info >= (3, 12) or sys.implementation.name != "cpython":
        return False  # True is immortal there
    leak = true_leak_per_emit()
    if leak <= 0:
        return False
    ctypes.c_ssize_t.from_address(id(True)).value += _BUMP
    _applied = True
    log.warning("Qt binding leaks %.1f reference(s) to True per signal; "
                "work-around applied (see app/ui/qt_fixes.py)", leak)
    return True
