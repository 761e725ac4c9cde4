"""The desk's start-up heap is moved out of the garbage collector's way."""

import gc

from app.ui.app import freeze_startup_heap


def test_objects_alive_at_start_up_are_frozen_and_later_ones_collected():
    kept = {"a start-up object": [1, 2, 3]}
    try:
        n = freeze_startup_heap()
        # frozen objects freed later (by reference count, e.g. on another thread)
        # leave the permanent generation, so the count can only have fallen since
        assert n >= gc.get_freeze_count() > 0
        # a full collection no longer walks what start-up made ...
        assert not any(o is kept for o in gc.get_objects(generation=2))
        # ... while what is made later is collected as before
        later = []
        later.append(later)  # a cycle: only the collector frees it
        assert any(o is later for o in gc.get_objects())
        gc.collect()
        del later
        assert gc.collect() >= 1
    finally:
        gc.unfreeze()
