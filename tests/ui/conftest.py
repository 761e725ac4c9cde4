import os

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

import pytest  # noqa: E402

import app.ui  # noqa: E402,F401  (applies the Qt binding work-arounds)

from .fakes import FakeLink  # noqa: E402


@pytest.fixture
def link(qtbot):
    return FakeLink()


@pytest.fixture
def window(qtbot, link):
    from app.ui.main_window import MainWindow

    win = MainWindow(link)
    qtbot.addWidget(win)
    win.resize(1280, 800)
    win.show()
    qtbot.waitExposed(win)
    link.set_state("connected")  # a desk on a working link (tests of no link drop it)
    return win
