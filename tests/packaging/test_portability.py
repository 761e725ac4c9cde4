"""Every module of the desk (app/) and of the simulator (sim_robot/) imports with the
Unix-only modules (tty, termios, fcntl, pty) unavailable, as on Windows.

A fresh interpreter refuses those modules when the code asking for them is the project's
own (a module under app/ or sim_robot/): an ``__import__`` hook for import statements
(a library may have loaded them already) and a meta-path finder for the rest. Third-party
code is left alone: pyserial, for one, picks its POSIX driver (termios, fcntl) on this
system and its Win32 driver on Windows, which this test cannot stand in for.

Exceptions (a module allowed to need them at import time, and why): none. The one
optional path, the simulated MCU on a pseudo-terminal (``sim-robot --mcu-link pty``,
``sim_robot.mcu_port.FdPort.pty``), imports ``tty`` only when asked for and says
"a pseudo-terminal needs a Unix system" otherwise; that too is checked here.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BLOCKED = ("tty", "termios", "fcntl", "pty")
# module -> why it may need a blocked module at import time (keep empty when possible)
ALLOWED: dict[str, str] = {}

_SCRIPT = r"""
import importlib, json, pkgutil, sys, traceback

BLOCKED = set(sys.argv[1].split(","))
OURS = ("app", "sim_robot")


def importer_name():
    f = sys._getframe(2)
    while f is not None:
        name = f.f_globals.get("__name__", "")
        if not (name.startswith("importlib") or name.startswith("_frozen_importlib")
                or name == "__blocker__"):
            return name
        f = f.f_back
    return ""


class Blocker:
    def find_spec(self, fullname, path=None, target=None):
        if fullname.split(".")[0] in BLOCKED:
            who = importer_name()
            if who.split(".")[0] in OURS:
                raise ModuleNotFoundError(f"{fullname} is Unix-only (imported by {who})",
                                          name=fullname)
        return None


Blocker.__module__ = "__blocker__"
for m in BLOCKED:
    sys.modules.pop(m, None)
sys.meta_path.insert(0, Blocker())  # importlib.import_module and first imports

import builtins
_import = builtins.__import__


def guarded_import(name, globals=None, locals=None, fromlist=(), level=0):
    # an import statement of the project's code, even of a module some library has
    # already loaded (those never reach the meta path again)
    who = (globals or {}).get("__name__", "")
    if level == 0 and name.split(".")[0] in BLOCKED and who.split(".")[0] in OURS:
        raise ModuleNotFoundError(f"{name} is Unix-only (imported by {who})", name=name)
    return _import(name, globals, locals, fromlist, level)


builtins.__import__ = guarded_import

result = {"failures": {}, "modules": 0, "probe": None, "pty_message": None}
# the blocker itself: project code asking for termios is refused, even once loaded
import termios  # as a library would
try:
    exec("import termios", {"__name__": "app._probe"})
    result["probe"] = "termios imported"
except ModuleNotFoundError as e:
    result["probe"] = str(e)

for top in OURS:
    pkg = importlib.import_module(top)
    names = [top] + [m.name for m in pkgutil.walk_packages(pkg.__path__, top + ".")]
    for name in names:
        if name.endswith("__main__"):
            continue  # runs a program when imported; its package is imported instead
        result["modules"] += 1
        try:
            importlib.import_module(name)
        except BaseException as e:  # noqa: BLE001 - SystemExit too: it is reported
            result["failures"][name] = f"{type(e).__name__}: {e}"

from sim_robot.mcu_port import open_mcu_port
try:
    open_mcu_port("pty").close()
except RuntimeError as e:
    result["pty_message"] = str(e)
print("RESULT" + json.dumps(result))
"""


def _run() -> dict:
    env = dict(os.environ, PYTHONPATH=str(ROOT), QT_QPA_PLATFORM="offscreen")
    out = subprocess.run([sys.executable, "-c", _SCRIPT, ",".join(BLOCKED)], cwd=ROOT,
                         env=env, capture_output=True, text=True, timeout=300)
    line = next((ln for ln in out.stdout.splitlines() if ln.startswith("RESULT")), None)
    assert line is not None, f"the import walk did not finish:\n{out.stderr[-3000:]}"
    return json.loads(line[len("RESULT"):])


def test_every_module_imports_without_unix_only_modules():
    r = _run()
    assert "Unix-only" in r["probe"], f"the blocker does not block: {r['probe']}"
    assert r["modules"] > 100  # the walk found the packages' modules
    failures = {m: why for m, why in r["failures"].items() if m not in ALLOWED}
    assert not failures, "modules that need Unix-only modules (or fail to import):\n" + \
        "\n".join(f"  {m}: {why}" for m, why in sorted(failures.items()))
    # the optional pty end says what is wrong instead of failing on import
    assert r["pty_message"] and "needs a Unix system" in r["pty_message"]
