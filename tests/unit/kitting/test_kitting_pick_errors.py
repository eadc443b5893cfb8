"""The picker tells a missed grasp from other aborted picks by the exception's type
(PickMissed), never by its message: a miss keeps the magnet on and is retried, any other
abort releases the magnet and ends the part's cycle."""

import pytest

from kitting.cell import load_cell
from kitting.picker import PickAborted, PickMissed

from .test_kitting_cell import _closed_loop, _run


@pytest.fixture(scope="module")
def cell():
    return load_cell()


def test_only_a_pick_missed_keeps_the_magnet_on_and_is_retried(cell):
    sim, fake, picker, events = _closed_loop(cell)
    sim.spawn("nut_yellow")
    # The second abort says "missed" too, but it is not a PickMissed: it counts as failed.
    aborts = iter(
        [
            PickMissed("missed: the part is still on the belt after the lift"),
            PickAborted("missed: a reason worded like a miss"),
        ]
    )

    def pick_and_place(track, t_grasp):
        raise next(aborts)

    picker._pick_and_place = pick_and_place
    _run(picker, fake, events, ("missed",))
    assert fake.gripper_calls == []  # nothing released after a miss
    _run(picker, fake, events, ("failed",))
    assert [on for _, on in fake.gripper_calls] == [False]
    assert [e.event for e in events if e.event in ("missed", "failed")] == ["missed", "failed"]
    assert issubclass(PickMissed, PickAborted)  # callers catching PickAborted see both
