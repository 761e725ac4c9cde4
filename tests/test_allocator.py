"""The desk's allocator setting: large buffers keep their own mappings (glibc)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from app.allocator import _glibc

# a 0.9 MB block (a decoded camera frame) allocated and freed three times: how many
# blocks had their own mapping while it was held (mallinfo2's hblks, glibc >= 2.33)
_PROBE = textwrap.dedent("""
    import ctypes, sys
    from app.allocator import settle_allocator
    class MallInfo2(ctypes.Structure):
        _fields_ = [(n, ctypes.c_size_t) for n in ("arena", "ordblks", "smblks", "hblks",
                    "hblkhd", "usmblks", "fsmblks", "uordblks", "fordblks", "keepcost")]
    libc = ctypes.CDLL("libc.so.6")
    libc.mallinfo2.restype = MallInfo2
    libc.malloc.restype = ctypes.c_void_p
    libc.free.argtypes = [ctypes.c_void_p]
    print(settle_allocator() if sys.argv[1] == "settle" else "-")
    before = libc.mallinfo2().hblks
    for _ in range(3):
        p = libc.malloc(921600)
        print(libc.mallinfo2().hblks - before)
        libc.free(p)
""")


ROOT = Path(__file__).resolve().parents[1]


def _run(mode: str, **env: str) -> list[str]:
    path = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p)
    env = {k: v for k, v in os.environ.items() if k != "MALLOC_MMAP_THRESHOLD_"} | env
    out = subprocess.run([sys.executable, "-c", _PROBE, mode], capture_output=True, text=True,
                         timeout=60, check=True, env={**env, "PYTHONPATH": path})
    return out.stdout.split()


def _has_mallinfo2() -> bool:
    libc = _glibc()
    return libc is not None and hasattr(libc, "mallinfo2")


@pytest.mark.skipif(not _has_mallinfo2(), reason="glibc >= 2.33 only (mallinfo2)")
def test_a_freed_frame_leaves_the_next_one_its_own_mapping():
    # glibc alone: after the first block is freed, the next ones come from the heap
    assert _run("plain") == ["-", "1", "0", "0"]
    # settled: every one has its own mapping, given back when freed
    assert _run("settle") == ["True", "1", "1", "1"]


@pytest.mark.skipif(_glibc() is None, reason="glibc only")
def test_the_operators_setting_is_kept():
    # a 4 MB threshold of the operator's: left alone, the frame comes from the heap
    assert _run("settle", MALLOC_MMAP_THRESHOLD_=str(4 << 20)) == ["False", "0", "0", "0"]


# 20 MB in 40 000 small blocks, all but every 20th freed: free holes inside the heap
# that glibc keeps (only the top of a heap goes back by itself); resident KiB printed
# held, after the holes, and after the trimmer has run once
_HOLES = textwrap.dedent("""
    import ctypes, sys
    from app.allocator import HeapTrimmer, _glibc
    def rss():
        for line in open("/proc/self/status"):
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    libc = _glibc()
    libc.malloc.restype = ctypes.c_void_p
    libc.free.argtypes = [ctypes.c_void_p]
    libc.memset.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_size_t]
    blocks = []
    for _ in range(40_000):
        p = libc.malloc(500)
        libc.memset(p, 1, 500)
        blocks.append(p)
    keep = libc.malloc(500)  # the top stays in use: nothing goes back by itself
    libc.memset(keep, 1, 500)
    held = rss()
    for i, p in enumerate(blocks):
        if i % 50:  # one block in 50 kept: 25 kB gaps, mostly whole pages to give back
            libc.free(p)
    holes = rss()
    trimmer = HeapTrimmer(libc, period_s=0.01).start()
    while trimmer.trims < 1:
        trimmer._stop.wait(0.01)
    trimmer.stop()
    print(held, holes, rss(), trimmer.trims >= 1, trimmer._thread.is_alive())
""")


@pytest.mark.skipif(_glibc() is None, reason="glibc only")
def test_the_trimmer_gives_free_holes_in_the_heap_back():
    held, holes, trimmed, ran, alive = _run_script(_HOLES)
    assert ran == "True" and alive == "False"
    assert int(holes) > int(held) - 2000  # freeing 19 MB inside the heap gave back ~nothing
    assert int(trimmed) < int(holes) - 10_000, (held, holes, trimmed)  # most of it went back


def _run_script(script: str) -> list[str]:
    path = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         timeout=60, check=True, env={**os.environ, "PYTHONPATH": path})
    return out.stdout.split()
