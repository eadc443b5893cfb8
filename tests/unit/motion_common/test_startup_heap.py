"""freeze_startup_heap: the start-up heap leaves the collector's scans."""

import gc

from motion_common.startup_heap import freeze_startup_heap


def test_the_start_up_heap_is_frozen_and_later_objects_are_still_collected():
    gc.unfreeze()
    try:
        startup = [[i] for i in range(5000)]  # long-lived, like a node's modules and models
        freeze_startup_heap()
        assert gc.get_freeze_count() >= len(startup)
        # Garbage made after the freeze (a reference cycle) is still found and freed.
        cycle = []
        cycle.append(cycle)
        del cycle
        assert gc.collect() >= 1
    finally:
        gc.unfreeze()  # the rest of the test session keeps the ordinary collector
