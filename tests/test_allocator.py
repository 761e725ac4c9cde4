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
