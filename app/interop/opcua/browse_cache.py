"""Browsing the desk's address space without walking the reference type tree each time.

A Browse (Part 4 §5.8.2) names a reference type and whether its subtypes count
(``IncludeSubtypes``; HierarchicalReferences with subtypes is what clients and
asyncua's own ``instantiate``, ``get_children`` and ``get_methods`` ask for). For every
reference of the browsed node asyncua's server walks the HasSubtype tree below the
asked type again (``ViewService._suitable_reftype`` → ``_get_sub_ref``). Making one
alarm condition browses some two hundred times: 60 % of its CPU went there (cProfile,
``bench/opcua_alarm_bench.py --profile``), and a client browsing the whole space pays
the same on the server's loop.

:func:`install` keeps the subtypes of each asked reference type (a frozen set, made on
first use) and answers from it. The answer is the same as asyncua's as long as no
reference type is added after the server starts: the desk adds none (its nodes use
the standard reference types), and its users sign in with asyncua's User role, which
may not add nodes (AddNodes is an Admin request). :func:`forget` empties
the sets (for a server that would add reference types).
"""

from __future__ import annotations

import logging
from typing import Any

from asyncua import ua

__all__ = ["forget", "install"]

log = logging.getLogger(__name__)

_NULL = ua.NodeId(ua.ObjectIds.Null)


def install(server: Any) -> bool:
    """Answer ``server``'s reference type checks from kept subtype sets; False (and a
    warning: browsing stays correct, only slower) when asyncua's view service is not
    as expected."""
    view = getattr(getattr(server, "iserver", None), "view_service", None)
    sub_refs = getattr(view, "_get_sub_ref", None)
    if view is None or sub_refs is None or not hasattr(view, "_suitable_reftype"):
        log.warning("OPC UA: asyncua's view service has changed; browsing is not cached")
        return False
    subtypes: dict[ua.NodeId, frozenset[ua.NodeId]] = {}

    def suitable_reftype(ref1: ua.NodeId, ref2: ua.NodeId, include_subtypes: bool) -> bool:
        # as asyncua's ViewService._suitable_reftype, with the subtypes kept
        if ref1 == _NULL or ref1 == ref2:  # no type asked: every reference
            return True
        if not include_subtypes:
            return False
        below = subtypes.get(ref1)
        if below is None:
            below = subtypes[ref1] = frozenset(sub_refs(ref1))
        return ref2 in below

    view._suitable_reftype = suitable_reftype
    view._subtype_sets = subtypes
    return True


def forget(server: Any) -> None:
    """Drop the kept subtype sets (after reference types were added)."""
    view = getattr(getattr(server, "iserver", None), "view_service", None)
    sets = getattr(view, "_subtype_sets", None)
    if sets is not None:
        sets.clear()
