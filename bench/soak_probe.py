"""What grows in a desk soak: object counts and Python allocations, start vs end.

Used by ``bench/desk_soak.py --probe``. Counts are taken from the live window:

- Qt objects under the window (``findChildren(QObject)``), top-level widgets;
- graphics items in every pyqtgraph scene and rows in every item view's model;
- the desk pipeline's series samples and the pages of its ring buffers in use;
- Python objects by type (``gc``), and ``tracemalloc`` differences by file and line;
- for the types that grew most, what holds their objects (``holders``).

``trim_rss`` calls glibc's ``malloc_trim(0)`` (when there is one) so that memory the
allocator holds but no longer uses can be told apart from memory still in use.
"""

from __future__ import annotations

import collections
import ctypes
import gc
import tracemalloc


def trim_rss() -> bool:
    try:
        return bool(ctypes.CDLL("libc.so.6").malloc_trim(0))
    except (OSError, AttributeError):
        return False


class _MallInfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in (
        "arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks",
        "uordblks", "fordblks", "keepcost")]


def malloc_kb() -> dict[str, int]:
    """glibc's own account (``mallinfo2``, all arenas), in KiB: bytes in use in the
    heaps (``in_use``, C++ and Python alike), free but kept in them (``free``), and
    in blocks with their own mapping (``mmapped``). Live memory grows ``in_use``;
    fragmentation grows ``free``. Empty where there is no glibc 2.33+."""
    try:
        fn = ctypes.CDLL("libc.so.6").mallinfo2
    except (OSError, AttributeError):
        return {}
    fn.restype = _MallInfo2
    m = fn()
    return {"malloc_kb:in_use": m.uordblks // 1024, "malloc_kb:free": m.fordblks // 1024,
            "malloc_kb:mmapped": m.hblkhd // 1024}


def sqlite_kb() -> int:
    """What the SQLite library holds (its page caches and statements), in KiB."""
    try:
        lib = ctypes.CDLL("libsqlite3.so.0")
        lib.sqlite3_memory_used.restype = ctypes.c_int64
        return int(lib.sqlite3_memory_used()) // 1024
    except (OSError, AttributeError):
        return -1


def rss_by_mapping() -> dict[str, int]:
    """Resident KiB by kind of mapping (/proc/self/smaps): the brk heap, anonymous
    mappings starting on a 64 MiB boundary (glibc thread arenas), other anonymous, and files."""
    out: dict[str, int] = collections.Counter()
    kind = ""
    try:
        with open("/proc/self/smaps") as f:
            for line in f:
                head = line.split()
                if "-" in head[0] and len(head) >= 5 and not head[0].endswith(":"):
                    a, b = (int(x, 16) for x in head[0].split("-"))
                    name = head[5] if len(head) > 5 else ""
                    kind = ("heap" if name == "[heap]" else
                            ("arena" if a % (64 << 20) == 0 else "anon") if not name else
                            "stack" if name.startswith("[stack") else
                            "lib" if ".so" in name else "file")
                elif head[0] == "Rss:":
                    out[kind] += int(head[1])
    except OSError:
        pass
    return {f"rss_kb:{k}": v for k, v in out.items()}


def count_objects(win) -> dict[str, int]:
    """Counts of the things that could grow without a bound, in one flat dict."""
    from PySide6.QtCore import QAbstractItemModel, QObject
    from PySide6.QtWidgets import (
        QAbstractItemView,
        QApplication,
        QGraphicsView,
        QPlainTextEdit,
    )

    out: dict[str, int] = {
        "qobjects": len(win.findChildren(QObject)),
        "top_widgets": len(QApplication.topLevelWidgets()),
    }
    for i, view in enumerate(win.findChildren(QGraphicsView)):
        scene = view.scene()
        if scene is not None:
            out[f"scene[{i}]:{type(view).__name__}@{type(view.parent()).__name__}"] = (
                len(scene.items()))
    for view in win.findChildren(QAbstractItemView):
        model = view.model()
        if isinstance(model, QAbstractItemModel):
            key = f"rows:{type(view).__name__}@{type(view.parent()).__name__}"
            out[key] = out.get(key, 0) + model.rowCount()
    for edit in win.findChildren(QPlainTextEdit):
        key = f"text_blocks:{type(edit.parent()).__name__}"
        out[key] = out.get(key, 0) + edit.blockCount()
    desk = getattr(win, "desk", None)
    pipe = getattr(desk, "pipeline", None)
    if pipe is not None:
        series = pipe.series
        out["series_samples"] = sum(len(series[c]) for c in series.channels)
    out["gc_objects"] = len(gc.get_objects())
    out["sqlite_kb"] = sqlite_kb()
    out.update(rss_by_mapping())
    out.update(malloc_kb())
    return out


def type_counts() -> collections.Counter:
    return collections.Counter(type(o).__name__ for o in gc.get_objects())


def diff_counts(a: dict[str, int], b: dict[str, int]) -> list[str]:
    lines = []
    for k in sorted(set(a) | set(b)):
        va, vb = a.get(k, 0), b.get(k, 0)
        lines.append(f"  {k}: {va} -> {vb} ({vb - va:+d})")
    return lines


def diff_types(a: collections.Counter, b: collections.Counter, top: int = 15) -> list[str]:
    d = sorted(((b[k] - a[k], k) for k in set(a) | set(b)), reverse=True)[:top]
    return [f"  {k}: {a[k]} -> {b[k]} ({n:+d})" for n, k in d if n]


def diff_tracemalloc(a: tracemalloc.Snapshot, b: tracemalloc.Snapshot, top: int = 20,
                     key: str = "lineno") -> list[str]:
    """The ``top`` allocation sites grown most from ``a`` to ``b``; with
    ``key="traceback"`` each with the frames that led to it (as many as traced)."""
    stats = b.compare_to(a, key)
    if key != "traceback":
        return [f"  {s}" for s in stats[:top]]
    lines = []
    for s in stats[:top]:
        lines.append(f"  {s.size_diff / 1024:+.1f} KiB, {s.count_diff:+d} blocks:")
        lines += [f"      {f.filename}:{f.lineno}" for f in s.traceback]
    return lines


GENERIC = {"tuple", "list", "dict", "set", "frozenset", "cell", "function", "method",
           "ReferenceType", "builtin_function_or_method", "frame"}


def _holder_name(ref, skip: set[int]) -> str:
    """A referrer's type; a ``__dict__`` or list/dict/deque named by what holds it."""
    name = type(ref).__name__
    if isinstance(ref, dict | list | collections.deque):
        owners = [o for o in gc.get_referrers(ref) if id(o) not in skip]
        for o in owners:
            d = getattr(o, "__dict__", None)
            if d is ref:
                return f"{type(o).__name__}.__dict__"
            if isinstance(d, dict):  # an attribute's value (3.11+ keeps no dict object)
                key = next((k for k, v in d.items() if v is ref), None)
                if key is not None:
                    return f"{name} in {type(o).__name__}.{key}"
        for o in owners:
            if isinstance(o, dict):
                for o2 in gc.get_referrers(o):
                    if getattr(o2, "__dict__", None) is o:
                        key = next((k for k, v in o.items() if v is ref), "?")
                        return f"{name} in {type(o2).__name__}.{key}"
        return name + (f" in {type(owners[0]).__name__}" if owners else "")
    return name


def holders(grown: list[str], top: int = 5) -> list[str]:
    """For each type name in ``grown``: what refers to its live objects, most often
    first (one pass over the referrers of all of them)."""
    by_type: dict[str, list] = {t: [] for t in grown}
    for o in gc.get_objects():
        objs = by_type.get(type(o).__name__)
        if objs is not None:
            objs.append(o)
    kind = {id(o): t for t, objs in by_type.items() for o in objs}
    everything = [o for objs in by_type.values() for o in objs]
    skip = {id(objs) for objs in by_type.values()} | {id(everything)}
    count: dict[str, collections.Counter] = {t: collections.Counter() for t in grown}
    for ref in gc.get_referrers(*everything):
        if id(ref) in skip:
            continue
        name = None
        for x in gc.get_referents(ref):
            t = kind.get(id(x))
            if t is not None:
                name = name or _holder_name(ref, skip)
                count[t][name] += 1
    lines = [f"  {t} ({len(by_type[t])}): " + ", ".join(
        f"{k} {v}" for k, v in count[t].most_common(top)) for t in grown]
    del everything, by_type
    return lines


def grown_types(a: collections.Counter, b: collections.Counter, top: int = 6) -> list[str]:
    """The non-generic types that grew most, start ``a`` to end ``b``."""
    d = sorted(((b[k] - a[k], k) for k in set(b) if k not in GENERIC), reverse=True)
    return [k for n, k in d[:top] if n > 0]
