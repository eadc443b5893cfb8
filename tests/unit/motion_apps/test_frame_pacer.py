"""The recorder's frame clock: a fast stream held between frames is read about 2-3 times a
frame instead of ~10, and the value at each frame is as fresh as reading every message."""

import threading
import time

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


def test_hold_lasts_until_the_window_before_the_next_tick():
    pacer = FramePacer(0.1, 0.015, clock=lambda: 0.0, start=0.0)
    assert pacer.hold_s(0.0) == pytest.approx(0.085)
    assert pacer.hold_s(0.09) == 0.0  # inside the window: read every message
    assert pacer.hold_s(0.1) == pytest.approx(0.085)  # the tick itself: hold for the next
    assert pacer.hold_s(0.25) == pytest.approx(0.035)
    assert FramePacer(0.01, 0.015, clock=lambda: 0.0, start=0.0).hold_s(0.003) == 0.0  # period under the window


def test_ticks_keep_their_schedule_and_skip_what_a_late_caller_missed():
    fake = FakeTime()
    pacer = FramePacer(0.1, 0.015, clock=fake, start=0.0, event=fake)
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
        FramePacer(0, 0.015)


@pytest.mark.parametrize("stream_period, phase", [(0.0095, 0.003), (0.008, 0.0), (0.0091, 0.0071)])
def test_held_stream_is_read_rarely_and_as_fresh_as_every_message(stream_period, phase):
    """A 100-125 Hz stream into a receive thread that holds after each read (as the recorder's
    callback does), sampled at 10 Hz ticks: the newest message read by each tick is the
    newest sent before it, and the thread wakes at most 3 times a frame."""
    pacer = FramePacer(0.1, 0.005, clock=lambda: 0.0, start=0.0)
    sent = [phase + j * stream_period for j in range(int(2.0 / stream_period))]
    reads = []  # (time of the read, newest message time it got)
    t, j = 0.0, 0
    while j < len(sent):
        t = max(t, sent[j])  # a blocking read returns with the next message
        while j + 1 < len(sent) and sent[j + 1] <= t:
            j += 1  # everything already in the socket comes at once
        reads.append((t, sent[j]))
        j += 1
        t += pacer.hold_s(t)
    for k in range(1, 19):
        tick = k * 0.1
        newest_sent = max(s for s in sent if s <= tick)
        newest_read = max(m for r, m in reads if r <= tick)
        assert newest_read == newest_sent, f"tick {tick}"
    assert len(reads) / 20 <= 3.0  # every message: 1 / stream_period / 10 = 8-12.5


def test_a_frame_waits_for_a_stream_woken_late_and_no_longer_than_told():
    """A stream still holding for this frame's window when the frame is due holds the
    frame back (its value would be a frame old); one holding for the next frame does not."""
    clock = {"now": 0.0}
    release = threading.Event()  # the hold below lasts until the test releases it
    pacer = FramePacer(0.1, 0.005, clock=lambda: clock["now"], start=0.0, event=release)
    clock["now"] = 0.02  # holds for the window of tick 0.1 (opens at 0.095)
    holder = threading.Thread(target=pacer.hold)
    holder.start()
    while not pacer.late(0.1):
        time.sleep(0.001)
    assert pacer.late(0.1) == 1 and pacer.late(0.09) == 0
    assert not pacer.caught_up(0.1, timeout=0.01)
    release.set()
    holder.join()
    assert pacer.caught_up(0.1, timeout=1.0)


def test_a_message_from_before_the_last_tick_does_not_hold():
    """Read late (after the tick), messages stamped before it are read on, so the frame
    after sees every one of them; the first one stamped after the tick holds."""
    fake = FakeTime()
    pacer = FramePacer(0.1, 0.005, clock=fake, start=0.0, event=fake)
    fake.now = 0.103
    pacer.hold(stamp=0.097)
    assert fake.now == 0.103  # not held
    pacer.hold(stamp=0.101)
    assert fake.now == pytest.approx(0.195)  # held until tick 0.2's window


def test_a_late_caller_gets_the_ticks_it_missed_up_to_catch_up():
    fake = FakeTime()
    pacer = FramePacer(0.1, 0.0, clock=fake, start=0.0, event=fake, catch_up=2)
    assert round(pacer.wait_tick(), 6) == 0.1
    fake.now += 0.37  # the caller stalls (0.47): ticks 0.2, 0.3 and 0.4 passed meanwhile
    ticks = [round(pacer.wait_tick(), 6) for _ in range(4)]
    assert ticks == [0.3, 0.4, 0.5, 0.6]  # 0.2 too old; 0.3 (made up) and 0.4 (late) at once
    assert (pacer.skipped, pacer.made_up) == (1, 1)
    assert fake.now == pytest.approx(0.6)


def _frames_of_a_stalled_recorder(catch_up):
    """A recorder's frames of a stream moving at 1 unit/s (100 Hz, tapped around each frame's
    instant, blended there), its ticking thread held up once for 0.25 s (a loaded machine)."""
    from motion_apps.stamped_history import StampedHistory, blend  # noqa: PLC0415
    from motion_common.frame_tap import FrameTap  # noqa: PLC0415

    fake = FakeTime()
    pacer = FramePacer(0.1, 0.0, clock=fake, start=0.02, event=fake, catch_up=catch_up)
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
