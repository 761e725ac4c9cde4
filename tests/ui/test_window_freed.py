"""A closed desk window is freed, with its session, panels and plots, while the link
it listened to lives on: the session's slots on the link hold it weakly and are
undone when it is deleted. (They held it strongly through the connection, which the
garbage collector cannot see: every window a test suite built stayed in memory,
15-25 MB each, 1.7 GB for tests/ui alone.)"""

import gc
import weakref

from PySide6.QtCore import QCoreApplication, QEvent, QObject

from .fakes import FakeLink


def _delete_later_now(obj) -> None:
    obj.deleteLater()
    QCoreApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete)


def test_a_closed_window_is_freed_while_its_link_lives_on(qtbot):
    from app.ui.main_window import MainWindow

    link = FakeLink()
    win = MainWindow(link)
    win.show()
    qtbot.waitExposed(win)
    window, session = weakref.ref(win), weakref.ref(win.desk)
    win.close()
    _delete_later_now(win)  # as qtbot does for the widgets it was given
    del win
    gc.collect()
    assert session() is None
    assert window() is None
    assert link.telemetry_received  # the link lives on


def test_a_deleted_session_stops_listening_to_the_link(qapp):
    from app.session import LINK_SIGNALS, DeskSession

    link = FakeLink()
    owner = QObject()
    desk = DeskSession(link, parent=owner)
    pipeline = desk.pipeline
    seen = []
    pipeline.ingest = lambda kind, msg: seen.append(kind)  # what the link delivers
    link.telemetry_received.emit({})
    assert seen == ["telemetry"]
    del desk
    _delete_later_now(owner)
    link.telemetry_received.emit({})
    link.pose_received.emit({})
    assert seen == ["telemetry"]
    assert "telemetry" in LINK_SIGNALS


def test_a_deleted_data_panel_is_freed_while_its_model_lives_on(qtbot):
    """The panel's slot on the model's alarm signal held the panel (a lambda): the
    deleted panel's plots and their menus stayed alive for the model's life."""
    from app.ui.data_panel import DataPanel
    from app.ui.models import TelemetryModel

    model = TelemetryModel(capacity=100, clock=lambda: 1_800_000_000.0)
    panel = DataPanel(model)
    freed = weakref.ref(panel)
    _delete_later_now(panel)
    del panel
    gc.collect()
    assert freed() is None
    model.monitor.update("gas_lel_pct", 30.0, 1_800_000_001.0)  # no panel: nothing raised
    assert model.monitor.is_active("gas_lel_pct.a2")


def test_connections_made_for_an_owner_s_life_go_with_it(qapp):
    from PySide6.QtCore import Signal

    from app.gui_gc import connect_for_life

    class Sender(QObject):
        ping = Signal(int)

    sender, owner, seen = Sender(), QObject(), []
    connect_for_life(owner, [(sender.ping, seen.append)])
    sender.ping.emit(1)
    _delete_later_now(owner)
    sender.ping.emit(2)
    assert seen == [1]
