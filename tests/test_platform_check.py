"""Missing Qt xcb libraries are found before Qt aborts (issue 12, C)."""

import sys

import pytest

from app import platform_check as pc

needs_plugin = pytest.mark.skipif(
    not sys.platform.startswith("linux") or pc.xcb_plugin() is None,
    reason="the PySide6 wheel's xcb plugin exists on Linux only")


def test_checked_only_when_the_window_would_use_xcb():
    assert pc.uses_xcb({"DISPLAY": ":0"}, "linux")
    assert pc.uses_xcb({"DISPLAY": ":0", "QT_QPA_PLATFORM": "xcb"}, "linux")
    assert not pc.uses_xcb({"DISPLAY": ":0", "QT_QPA_PLATFORM": "offscreen"}, "linux")
    assert not pc.uses_xcb({}, "linux")  # no display: headless anyway
    assert not pc.uses_xcb({"DISPLAY": ":0"}, "darwin")
    assert not pc.uses_xcb({"DISPLAY": ":0", "WAYLAND_DISPLAY": "wayland-0",
                            "XDG_SESSION_TYPE": "wayland"}, "linux")


@needs_plugin
def test_the_plugins_links_are_read_from_the_elf_file():
    needed = pc.elf_needed(pc.xcb_plugin())
    assert "libQt6XcbQpa.so.6" in needed and "libQt6Gui.so.6" in needed


@needs_plugin
def test_every_missing_library_is_named_with_its_package():
    gone = {"libxcb-cursor.so.0", "libxcb-icccm.so.4", "libxcb-keysyms.so.1"}

    def load(soname):
        if soname in gone:
            return f"{soname}: cannot open shared object file: No such file or directory"
        if soname == "libxcb-image.so.0":  # present, but needs a missing one
            return "libxcb-util.so.1: cannot open shared object file: No such file or directory"
        return None

    missing = pc.missing_libraries(pc.xcb_plugin(), load)
    assert {m.soname for m in missing} == gone | {"libxcb-util.so.1"}
    text = pc.message(missing)
    assert "sudo apt install libxcb-cursor0 libxcb-icccm4 libxcb-keysyms1 libxcb-util1" in text
    for soname in gone:
        assert soname in text
    assert pc.missing_libraries(pc.xcb_plugin(), lambda _s: None) == []


@needs_plugin
def test_the_desk_says_so_and_exits_before_qt_aborts(monkeypatch, capsys):
    from app.cli import main

    monkeypatch.setenv("DISPLAY", ":99")
    monkeypatch.delenv("QT_QPA_PLATFORM", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(pc, "_dlopen", lambda s: f"{s}: cannot open shared object file"
                        if s == "libxcb-cursor.so.0" else None)
    assert main(["--connect", "127.0.0.1:9"]) == 1
    err = capsys.readouterr().err
    assert "libxcb-cursor.so.0  (package libxcb-cursor0)" in err
    assert "sudo apt install libxcb-cursor0" in err and "--headless" in err
