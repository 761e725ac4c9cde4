"""The OPC UA standard address space, kept on disk between server starts.

asyncua builds the standard address space (the ≈ 5,000 nodes of the OPC UA
specification's types and the Server object) from generated Python code on every
start: ≈ 2.4 s of CPU, most of the server's start. It can instead keep those nodes
in a :mod:`shelve` and load each one when it is first touched
(``Server.init(shelf_file)``, asyncua's ``load_aspace_shelf``): ≈ 0.1 s.

The shelf is made once per asyncua and Python version, on the first start, in the
desk's cache folder (:func:`app.core.paths.cache_dir`), right after the standard
nodes are built and before the desk adds its own (it must hold the specification's
nodes only). It is written into a folder of its own and moved into place in one
rename, so two servers starting at once never read half a shelf; the loser of that
race throws its copy away. A shelf that cannot be loaded is deleted and the server
builds its address space as before; the next start makes the shelf again.

asyncua decides whether a shelf exists by its file name (``PATH`` or ``PATH.db``);
:mod:`dbm.dumb`, the fallback where Python has no gdbm/ndbm, writes ``PATH.dat`` and
``PATH.dir`` instead, so an empty ``PATH`` is written beside them (``dbm.whichdb``
looks at ``.dat``/``.dir`` before it reads ``PATH`` itself).
"""

from __future__ import annotations

import asyncio
import logging
import os
import shutil
import sys
import time
from collections.abc import Callable
from pathlib import Path

import asyncua
from asyncua import Server

from app.core.paths import cache_dir

log = logging.getLogger(__name__)

SHELF = "aspace"


def shelf_folder(root: Path | None = None) -> Path:
    """The shelf's folder for this asyncua and Python (a new version: a new shelf)."""
    v = sys.version_info
    return (root or cache_dir()) / f"opcua-aspace-{asyncua.__version__}-py{v.major}{v.minor}"


def _ready(folder: Path) -> bool:
    return (folder / "complete").is_file()


async def initialised(make_server: Callable[[], Server], *, enabled: bool = True,
                      root: Path | None = None) -> tuple[Server, str]:
    """A server from ``make_server()`` with its standard address space loaded, and how:
    ``"shelf"`` (loaded from the cache), ``"made"`` (built, and the cache made),
    ``"built"`` (built; the cache off or not writable)."""
    folder = shelf_folder(root)
    if enabled and _ready(folder):
        server = make_server()
        t0 = time.process_time()
        try:
            await server.init(folder / SHELF)
        except Exception as e:  # a damaged or foreign shelf: forget it, build as before
            log.warning("OPC UA: the cached address space in %s could not be loaded (%s: %s); "
                        "building it", folder, type(e).__name__, e)
            shutil.rmtree(folder, ignore_errors=True)
        else:
            log.info("OPC UA: standard address space loaded from %s in %.2f s of CPU",
                     folder, time.process_time() - t0)
            return server, "shelf"
    if not enabled:
        server = make_server()
        await server.init()
        return server, "built"
    tmp = folder.with_name(f"{folder.name}.tmp-{os.getpid()}")
    try:
        shutil.rmtree(tmp, ignore_errors=True)
        tmp.mkdir(parents=True)
        server = make_server()
        t0 = time.process_time()
        # asyncua writes the shelf while it builds the standard nodes, before anything
        # else (the condition methods' callbacks, the desk's nodes) joins them
        await server.init(tmp / SHELF)
        await asyncio.to_thread(_publish, tmp, folder, time.process_time() - t0)
    except OSError as e:  # a read-only or full disk: serve without the cache
        log.warning("OPC UA: could not cache the standard address space in %s: %s", folder, e)
        shutil.rmtree(tmp, ignore_errors=True)
        server = make_server()
        await server.init()
        return server, "built"
    return server, "made"


def _publish(tmp: Path, folder: Path, cpu_s: float) -> None:
    """Move the shelf written in the private folder ``tmp`` into place in one rename."""
    try:
        marker = tmp / SHELF
        if not marker.exists() and not marker.with_suffix(".db").exists():
            marker.touch()  # dbm.dumb: the name asyncua looks for
        (tmp / "complete").write_text(f"asyncua {asyncua.__version__}\n")
        try:
            os.rename(tmp, folder)
        except OSError:
            if not _ready(folder):  # not another server's shelf in the way
                raise
        else:
            log.info("OPC UA: standard address space built and cached in %s (%.2f s of CPU)",
                     folder, cpu_s)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
