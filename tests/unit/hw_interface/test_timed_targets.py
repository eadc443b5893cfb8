"""The simulation's streamed targets by arrival time: a physics thread that runs its steps
late, in a burst, applies to each step the target in force at the step's scheduled time."""

from hw_interface.timed_targets import TimedTargets


def test_a_burst_of_late_steps_applies_each_the_target_in_force_at_its_schedule():
    targets = TimedTargets()
    for k in range(5):  # a 100 Hz stream: targets 0..4 arrive at 1, 11, 21, 31, 41 ms
        targets.add(0.001 + 0.01 * k, k)
    # The thread wakes at 45 ms and runs the 2 ms steps scheduled from 0 to 44 ms back to
    # back: the newest target (4) must not drive the steps scheduled before it arrived.
    applied = [targets.due(0.002 * step) for step in range(23)]
    changes = {step: goal for step, goal in enumerate(applied) if goal is not None}
    assert changes == {1: 0, 6: 1, 11: 2, 16: 3, 21: 4}
    assert len(targets) == 0


def test_targets_in_one_step_leave_together_and_the_newest_wins():
    targets = TimedTargets()
    targets.add(0.0101, "a")
    targets.add(0.0102, "b")
    assert targets.due(0.010) is None
    assert targets.due(0.012) == "b"
    assert targets.due(0.014) is None  # nothing new: the follower keeps its goal


def test_a_target_stamped_before_the_newest_keeps_arrival_order():
    targets = TimedTargets()
    targets.add(0.020, "first")
    targets.add(0.015, "second")  # a clock step back: still after the first
    assert targets.due(0.016) is None
    assert targets.due(0.020) == "second"


def test_clear_drops_every_queued_target_and_the_queue_is_bounded():
    targets = TimedTargets(maxlen=4)
    for k in range(10):
        targets.add(float(k), k)
    assert len(targets) == 4 and targets.due(100.0) == 9
    targets.add(200.0, "before a stop")
    targets.clear()
    assert targets.due(300.0) is None
