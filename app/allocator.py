"""Keep a long-running desk's memory from creeping under glibc's allocator (Linux).

The desk allocates many large, short-lived buffers: every camera frame is decoded
into a 0.9 MB array on the link thread and let go on the GUI thread, a dozen times
a second. glibc serves a block that large with its own memory mapping, returned to
the system when freed, but it raises that threshold to the size of each such block
freed (its "dynamic mmap threshold"): after the first frame, frames come from the
threads' heaps, where freed blocks are kept and fragment: after ten minutes of a
desk soak, 11 MB of its resident memory was such kept memory (``malloc_trim`` gave
it back).

:func:`settle_allocator` fixes the threshold (``mallopt(M_MMAP_THRESHOLD)``, which
also turns the dynamic adjustment off), so large buffers keep their own mappings
and go back to the system when freed. Elsewhere (macOS, Windows, musl) it does
nothing; an operator's ``MALLOC_MMAP_THRESHOLD_`` setting is left as it is.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import logging
import os
import sys

log = logging.getLogger(__name__)

__all__ = ["MMAP_THRESHOLD_BYTES", "settle_allocator"]

M_MMAP_THRESHOLD = -3  # glibc's mallopt parameter number
MMAP_THRESHOLD_BYTES = 128 * 1024  # glibc's own starting value


def _glibc():
    if not sys.platform.startswith("linux"):
        return None
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        libc.gnu_get_libc_version  # noqa: B018 - glibc only: musl has no such function
        return libc
    except (OSError, AttributeError):
        return None


def settle_allocator(threshold_bytes: int = MMAP_THRESHOLD_BYTES) -> bool:
    """Fix glibc's mmap threshold at ``threshold_bytes``; True when it was set."""
    if "MALLOC_MMAP_THRESHOLD_" in os.environ:
        return False  # the operator chose it
    libc = _glibc()
    if libc is None:
        return False
    ok = bool(libc.mallopt(M_MMAP_THRESHOLD, int(threshold_bytes)))
    if ok:
        log.debug("allocator: blocks from %d bytes get their own mapping", threshold_bytes)
    else:
        log.warning("allocator: mallopt(M_MMAP_THRESHOLD, %d) refused", threshold_bytes)
    return ok
