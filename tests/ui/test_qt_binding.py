"""The Qt binding must not leak references to Python's singletons.

PySide6 6.12.0 on Python 3.11 drops one reference to ``True`` per signal
emission and to ``None`` per call of a Python override; after a few hundred
thousand calls the interpreter aborts ("Fatal Python error: bool_dealloc").
pyproject.toml excludes that release; this test catches a binding that brings
the defect back.
"""

import sys

from PySide6.QtCore import QObject, Signal


class _Probe(QObject):
    fired = Signal(object)

    def childEvent(self, event):  # noqa: N802 (Qt name)
        return None


def test_signal_emission_and_overrides_keep_singleton_refcounts(qapp):
    probe = _Probe()
    probe.fired.connect(lambda _x: None)
    n = 1000
    t0, n0 = sys.getrefcount(True), sys.getrefcount(None)
    for _ in range(n):
        probe.fired.emit(0)
        QObject(probe).setParent(None)
    lost_true = t0 - sys.getrefcount(True)
    lost_none = n0 - sys.getrefcount(None)
    # a per-call leak would lose thousands; caches may hold a few hundred
    assert lost_true < n / 10, f"binding leaks True: {lost_true} refs over {n} emits"
    assert lost_none < n / 10, f"binding leaks None: {lost_none} refs over {n} calls"
