"""Before the window opens: can Qt's xcb platform plugin load on this machine?

On a stock Debian or Ubuntu desktop the PySide6 wheel's xcb plugin needs X11
libraries that are often not installed (libxcb-cursor0, libxcb-icccm4,
libxcb-keysyms1, ...). Qt then aborts with "Could not load the Qt platform
plugin xcb", naming at most one library, and sometimes the wrong one. This
module finds every missing one first, without importing Qt:

1. the plugin's file and the Qt libraries beside it come from the installed
   PySide6 package (found by ``importlib``, not imported);
2. their ``DT_NEEDED`` entries (the shared libraries they link against) are read
   from the ELF files; the Qt libraries shipped in the wheel are followed, the
   system ones are opened with ``dlopen`` (``ctypes.CDLL``) exactly as the
   dynamic loader would when Qt loads the plugin;
3. each one that does not open is reported with the Debian/Ubuntu package that
   provides it and one ``apt install`` line.

Checked only when the window would use xcb: on Linux, with ``DISPLAY`` set and
``QT_QPA_PLATFORM`` unset (outside a Wayland session) or ``xcb``.
"""

from __future__ import annotations

import ctypes
import importlib.util
import logging
import os
import re
import struct
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

log = logging.getLogger(__name__)

__all__ = ["MissingLibrary", "check_xcb", "elf_needed", "message", "missing_libraries",
           "uses_xcb", "xcb_plugin"]

# soname -> Debian/Ubuntu package (the ones the xcb plugin and Qt's GUI library need)
PACKAGES: dict[str, str] = {
    "libxcb-cursor.so.0": "libxcb-cursor0", "libxcb-icccm.so.4": "libxcb-icccm4",
    "libxcb-keysyms.so.1": "libxcb-keysyms1", "libxcb-image.so.0": "libxcb-image0",
    "libxcb-render-util.so.0": "libxcb-render-util0", "libxcb-shape.so.0": "libxcb-shape0",
    "libxcb-xkb.so.1": "libxcb-xkb1", "libxcb-randr.so.0": "libxcb-randr0",
    "libxcb-xfixes.so.0": "libxcb-xfixes0", "libxcb-sync.so.1": "libxcb-sync1",
    "libxcb-shm.so.0": "libxcb-shm0", "libxcb-render.so.0": "libxcb-render0",
    "libxcb-util.so.1": "libxcb-util1", "libxcb-xinput.so.0": "libxcb-xinput0",
    "libxcb-glx.so.0": "libxcb-glx0", "libxcb.so.1": "libxcb1",
    "libxkbcommon-x11.so.0": "libxkbcommon-x11-0", "libxkbcommon.so.0": "libxkbcommon0",
    "libX11-xcb.so.1": "libx11-xcb1", "libX11.so.6": "libx11-6", "libSM.so.6": "libsm6",
    "libICE.so.6": "libice6", "libfontconfig.so.1": "libfontconfig1",
    "libfreetype.so.6": "libfreetype6", "libEGL.so.1": "libegl1", "libGL.so.1": "libgl1",
    "libOpenGL.so.0": "libopengl0", "libglib-2.0.so.0": "libglib2.0-0",
    "libgthread-2.0.so.0": "libglib2.0-0", "libdbus-1.so.3": "libdbus-1-3",
}
_NOT_FOUND = re.compile(r"(lib[\w.+-]+\.so[\w.]*): cannot open shared object file")


@dataclass(frozen=True)
class MissingLibrary:
    soname: str
    package: str  # "" when not known
    why: str  # the loader's message


def uses_xcb(env: Mapping[str, str] | None = None, platform: str | None = None) -> bool:
    """True when a Qt window would use the xcb plugin (so it is worth checking)."""
    env = os.environ if env is None else env
    if not (platform or sys.platform).startswith("linux") or not env.get("DISPLAY"):
        return False
    qpa = env.get("QT_QPA_PLATFORM", "")
    if qpa:
        return qpa.split(":", 1)[0].split(";", 1)[0] == "xcb"
    return not (env.get("WAYLAND_DISPLAY") and env.get("XDG_SESSION_TYPE") == "wayland")


def xcb_plugin() -> Path | None:
    """The installed PySide6's ``libqxcb.so``, found without importing Qt."""
    spec = importlib.util.find_spec("PySide6")
    if spec is None or not spec.submodule_search_locations:
        return None
    p = Path(list(spec.submodule_search_locations)[0]) / "Qt/plugins/platforms/libqxcb.so"
    return p if p.is_file() else None


def elf_needed(path: Path) -> list[str]:
    """The ``DT_NEEDED`` sonames of an ELF shared object (read from its
    ``SHT_DYNAMIC`` section and the string table it links to)."""
    data = Path(path).read_bytes()
    if data[:4] != b"\x7fELF":
        raise ValueError(f"{path} is not an ELF file")
    is64, order = data[4] == 2, "<" if data[5] == 1 else ">"
    if is64:
        shoff, = struct.unpack_from(order + "Q", data, 0x28)
        shentsize, shnum = struct.unpack_from(order + "HH", data, 0x3A)
        sh = struct.Struct(order + "IIQQQQIIQQ")  # name type flags addr offset size link ...
        dyn = struct.Struct(order + "qQ")
    else:
        shoff, = struct.unpack_from(order + "I", data, 0x20)
        shentsize, shnum = struct.unpack_from(order + "HH", data, 0x2E)
        sh = struct.Struct(order + "IIIIIIIIII")
        dyn = struct.Struct(order + "iI")
    sections = [sh.unpack_from(data, shoff + i * shentsize) for i in range(shnum)]
    out: list[str] = []
    for s in sections:
        if s[1] != 6:  # SHT_DYNAMIC
            continue
        str_off = sections[s[6]][4]
        for off in range(s[4], s[4] + s[5], dyn.size):
            tag, val = dyn.unpack_from(data, off)
            if tag == 0:  # DT_NULL
                break
            if tag == 1:  # DT_NEEDED
                end = data.index(b"\0", str_off + val)
                out.append(data[str_off + val:end].decode("ascii", "replace"))
    return out


def _dlopen(soname: str) -> str | None:
    """None when the library (and everything it needs) loads, else the loader's message."""
    try:
        ctypes.CDLL(soname)
    except OSError as e:
        return str(e)
    return None


def missing_libraries(plugin: Path, load: Callable[[str], str | None] | None = None
                      ) -> list[MissingLibrary]:
    """The system libraries ``plugin`` needs that do not load, in link order
    (``load``: how to try one; by default ``dlopen``)."""
    load = load or _dlopen
    qt_lib = plugin.parent.parent.parent / "lib"  # PySide6/Qt/lib beside plugins/
    missing: dict[str, MissingLibrary] = {}
    seen: set[str] = set()
    todo = [plugin]
    while todo:
        f = todo.pop(0)
        for name in elf_needed(f):
            if name in seen:
                continue
            seen.add(name)
            if (qt_lib / name).is_file():  # shipped in the wheel: what does it need?
                todo.append(qt_lib / name)
                continue
            why = load(name)
            if why is None:
                continue
            # a library that is there but needs a missing one: report the missing one
            m = _NOT_FOUND.search(why)
            real = m.group(1) if m else name
            missing.setdefault(real, MissingLibrary(real, PACKAGES.get(real, ""), why))
    return list(missing.values())


def message(missing: list[MissingLibrary]) -> str:
    """What to tell the operator: every missing library and the install line."""
    lines = ["the window cannot open: Qt's xcb platform plugin needs system libraries "
             "that are not installed:"]
    for m in missing:
        lines.append(f"  {m.soname}" + (f"  (package {m.package})" if m.package else ""))
    pkgs = sorted({m.package for m in missing if m.package})
    if pkgs:
        lines.append("install them with:")
        lines.append("  sudo apt install " + " ".join(pkgs))
    unknown = [m.soname for m in missing if not m.package]
    if unknown:
        lines.append("find the package of the others with: apt-file search " + unknown[0])
    lines.append("or run without a window: add --headless")
    return "\n".join(lines)


def check_xcb(env: Mapping[str, str] | None = None) -> str | None:
    """None when the window can use xcb (or does not use it); else the message."""
    if not uses_xcb(env):
        return None
    plugin = xcb_plugin()
    if plugin is None:
        return None  # not a PySide6 wheel layout: let Qt speak for itself
    try:
        missing = missing_libraries(plugin)
    except (OSError, ValueError, struct.error, IndexError) as e:
        log.warning("could not check Qt's xcb plugin (%s); trying the window anyway", e)
        return None
    return message(missing) if missing else None
