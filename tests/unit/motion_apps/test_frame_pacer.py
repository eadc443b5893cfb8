"""The recorder's frame clock: ticks keep their schedule, and a caller held up past ticks
gets the ones it missed (up to catch_up), so no frame stands for a later instant than its
place in the episode says."""

import pytest

from motion_apps.frame_pacer import FramePacer


class FakeTime:
    """A clock and an Event whose wait advances the clock (never sleeps)."""

    def __init__(self):
        self.now = 0.0
        self.stopped = False

    def __call__(self):
        return self.now

    def wait(self, seconds):
        self.now += max(0.0, seconds)
        return self.stopped

    def set(self):
        self.stopped = True

    def is_set(self):
        return self.stopped


def test_ticks_keep_their_schedule_and_skip_what_a_late_caller_missed():
    fake = FakeTime()
    pacer = FramePacer(0.1, clock=fake, start=0.0, event=fake)
    ticks = []
    for _ in range(3):
        ticks.append(round(pacer.wait_tick(), 6))
        assert fake.now == pytest.approx(ticks[-1])
        fake.now += 0.02  # the frame's own work
    fake.now += 0.35  # the caller stalls for 3.5 periods
    ticks.append(round(pacer.wait_tick(), 6))
    assert ticks == [0.1, 0.2, 0.3, 0.7]  # 0.4-0.6 passed while it stalled
    fake.set()
    assert pacer.wait_tick() is None


def test_bad_period_is_refused():
    with pytest.raises(ValueError, match="period 0 s"):
        FramePacer(0)


def test_a_late_caller_gets_the_ticks_it_missed_up_to_catch_up():
    fake = FakeTime()
    pacer = FramePacer(0.1, clock=fake, start=0.0, event=fake, catch_up=2)
    assert round(pacer.wait_tick(), 6) == 0.1
    fake.now += 0.37  # the caller stalls (0.47): ticks 0.2, 0.3 and 0.4 passed meanwhile
    ticks = [round(pacer.wait_tick(), 6) for _ in range(4)]
    assert ticks == [0.3, 0.4, 0.5, 0.6]  # 0.2 too old; 0.3 (made up) and 0.4 (late) at once
    assert (pacer.skipped, pacer.made_up) == (1, 1)
    assert fake.now == pytest.approx(0.6)


def _frames_of_a_stalled_recorder(catch_up):
    """A recorder's frames of a stream moving at 1 unit/s (100 Hz, tapped around each frame's
    instant, blended there), its ticking thread held up once for 0.25 s (a loaded machine)."""
    from motion_apps.stamped_history import StampedHistory  # noqa: PLC0415
    from motion_common.frame_blend import blend  # noqa: PLC0415
    from motion_common.frame_tap import FrameTap  # noqa: PLC0415

    fake = FakeTime()
    pacer = FramePacer(0.1, clock=fake, start=0.02, event=fake, catch_up=catch_up)
    history = StampedHistory()
    tap = FrameTap(lambda stamp: history.add(stamp, [stamp]), lambda: True, 0.1)
    fed = 0.0
    frames = []
    for k in range(12):
        tick = pacer.wait_tick()
        while fed <= fake.now:  # the stream's messages up to now have come
            tap.add(fed, fed)
            fed = round(fed + 0.01, 6)
        (_, before), (_, after), u = history.around(tick - 0.02)
        frames.append(float(blend(before, after, u)[0]))
        if k == 4:
            fake.now += 0.25
    return frames


def test_a_stalled_recorder_makes_up_its_frames_at_their_own_instants():
    # Each frame stands for its own instant, 0.1 s after the one before: a frame skipped would
    # leave a 0.2 s step where the episode's fixed rate says 0.1 s (a replay then lags by the
    # arm's travel in 0.1 s: 4-14 mm at the teach demo's speeds).
    made_up = _frames_of_a_stalled_recorder(catch_up=4)
    assert [round(b - a, 6) for a, b in zip(made_up, made_up[1:])] == [0.1] * 11
    skipped = _frames_of_a_stalled_recorder(catch_up=0)
    assert max(b - a for a, b in zip(skipped, skipped[1:])) == pytest.approx(0.3)
