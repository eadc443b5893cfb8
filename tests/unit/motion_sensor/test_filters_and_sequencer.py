"""Mean filter, quaternion averaging and the sequencer's drop rules."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from motion_sensor.errors import MotionSensorError
from motion_sensor.hand_sample import HandSample
from motion_sensor.sequencing.filters import MeanFilter, average_quaternions, make_filter
from motion_sensor.sequencing.sequencer import Sequencer, SequencerConfig

IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


def sample(stamp, position=(0.0, 0.0, 0.2), orientation=IDENTITY, **kw):
    return HandSample(
        stamp=stamp, position=np.array(position, dtype=float), orientation=np.array(orientation, dtype=float), **kw
    )


def test_mean_filter_averages_the_last_ten():
    f = MeanFilter()
    for i in range(15):
        position, orientation = f.update(i, np.array([i, 0.0, 0.0]), IDENTITY)
    assert position[0] == pytest.approx(np.mean(range(5, 15)))
    np.testing.assert_allclose(orientation, IDENTITY)


def test_quaternion_average_ignores_sign_and_stays_unit(rng):
    base = Rotation.from_euler("xyz", [0.3, -0.2, 1.0])
    rotations = base * Rotation.from_rotvec(rng.normal(0, 0.02, (10, 3)))
    quats = rotations.as_quat()
    quats[::2] *= -1  # the same rotations with flipped signs
    mean = average_quaternions(quats)
    assert np.linalg.norm(mean) == pytest.approx(1.0)
    # scipy's chordal mean of the unflipped rotations is the reference answer.
    assert (Rotation.from_quat(mean) * rotations.mean().inv()).magnitude() < 1e-9
    assert (Rotation.from_quat(mean) * base.inv()).magnitude() < 0.05


@settings(max_examples=50, deadline=None)
@given(st.lists(st.lists(st.floats(-1, 1), min_size=4, max_size=4), min_size=1, max_size=10))
def test_quaternion_average_is_always_unit(raw):
    quats = np.array(raw, dtype=float)
    norms = np.linalg.norm(quats, axis=1)
    quats = quats[norms > 1e-3] / norms[norms > 1e-3, None]
    if len(quats):
        assert np.linalg.norm(average_quaternions(quats)) == pytest.approx(1.0)


def test_unknown_filter_and_bad_queue_are_explained():
    with pytest.raises(MotionSensorError, match="unknown filter"):
        make_filter("median")
    with pytest.raises(MotionSensorError, match="queue_size"):
        make_filter("mean", queue_size=0)


def plain(**kw):
    """A sequencer with no trimming, so single frames pass straight through; the paper's
    mean filter unless told otherwise (the tests count frames through its window)."""
    kw.setdefault("filter_name", "mean")
    return Sequencer(SequencerConfig(entry_trim_frames=0, **kw))


def test_sequencer_passes_good_frames_and_counts():
    seq = plain()
    out = seq.process(sample(10.0), now=10.01)
    assert out is not None and out.stamp == 10.0
    assert seq.counters["frames_out"] == 1 and seq.dropped == 0


@pytest.mark.parametrize(
    "bad, reason",
    [
        (dict(position=(np.nan, 0, 0)), "non_finite"),
        (dict(orientation=(0, 0, 0, 2.0)), "non_unit_quaternion"),
        (dict(orientation=(0, 0, 0, 0)), "non_unit_quaternion"),
        (dict(hands_num=2), "hands_num_mismatch"),
        (dict(position=(0.0, 0.1)), "malformed"),
        (dict(position=np.zeros((3, 1))), "malformed"),
        (dict(orientation=(0, 0, np.inf, 1)), "non_finite"),
        (dict(position=(0, 0, 0.2, 0.1)), "malformed"),
    ],
)
def test_sequencer_drops_bad_frames(bad, reason):
    seq = plain()
    assert seq.process(sample(10.0, **bad), now=10.0) is None
    assert seq.counters["dropped_" + reason] == 1


def test_sequencer_drops_stale_duplicate_out_of_order_and_future():
    seq = plain(max_age_s=0.1)
    assert seq.process(sample(10.0), now=10.2) is None  # older than max age
    assert seq.process(sample(10.0), now=10.01) is not None
    assert seq.process(sample(10.0), now=10.02) is None  # duplicate
    assert seq.process(sample(9.99), now=10.02) is None  # out of order
    assert seq.process(sample(11.0), now=10.02) is None  # from the future
    assert seq.process(sample(-1.0), now=10.02) is None  # negative stamp
    assert seq.process(sample(10.05), now=10.06) is not None
    counts = seq.counters
    assert (
        counts["dropped_stale"],
        counts["dropped_duplicate"],
        counts["dropped_out_of_order"],
        counts["dropped_future_stamp"],
        counts["dropped_bad_stamp"],
    ) == (1, 1, 1, 1, 1)
    assert seq.dropped == 5


def test_new_hand_reseeds_the_filter_instead_of_blending():
    seq = plain()
    for i in range(5):
        seq.process(sample(10.0 + 0.01 * i, position=(0.0, 0.0, 0.2), hand_id=1), now=10.1)
    out = seq.process(sample(10.1, position=(0.1, 0.0, 0.2), hand_id=2), now=10.1)
    np.testing.assert_allclose(out.position, [0.1, 0.0, 0.2])
    assert seq.counters["filter_reseeds"] == 1


def test_frame_without_hand_is_counted_not_an_error():
    seq = Sequencer()
    empty = HandSample(stamp=10.0, position=np.zeros(3), orientation=np.zeros(4), hands_num=0, hand_types=())
    assert seq.process(empty, now=10.0) is None
    assert seq.counters["dropped_no_hand"] == 1


def test_bad_config_is_refused():
    with pytest.raises(MotionSensorError, match="max_age_s"):
        SequencerConfig(max_age_s=0)


def stream(seq, positions, start=10.0, dt=0.01, **kw):
    """Feed positions at a fixed rate; return the outputs (None for dropped frames)."""
    return [seq.process(sample(start + i * dt, position=p, **kw), now=start + i * dt) for i, p in enumerate(positions)]


def test_entry_trim_drops_the_first_frames_of_a_hand():
    seq = Sequencer(SequencerConfig(entry_trim_frames=3))
    out = stream(seq, [(0, 0, 0.2)] * 5)
    assert [o is None for o in out] == [True, True, True, False, False]
    assert seq.counters["dropped_entry_trim"] == 3
    # The hand leaves (a gap longer than hand_lost_s) and comes back: trimmed again.
    again = stream(seq, [(0, 0, 0.2)] * 4, start=11.0)
    assert [o is None for o in again] == [True, True, True, False]


def test_exit_trim_discards_the_last_frames_before_the_hand_leaves():
    seq = Sequencer(SequencerConfig(entry_trim_frames=0, exit_trim_frames=2))
    out = stream(seq, [(0.001 * i, 0, 0.2) for i in range(5)])
    assert [o is None for o in out] == [True, True, False, False, False]
    assert out[2].position[0] == pytest.approx(0.0)  # delayed by two frames
    empty = HandSample(stamp=10.06, position=np.zeros(3), orientation=np.zeros(4), hands_num=0, hand_types=())
    seq.process(empty, now=10.06)
    assert seq.counters["dropped_exit_trim"] == 2


def test_a_single_jump_is_ignored():
    seq = plain(filter_name="one_euro")
    path = [(0.001 * i, 0, 0.2) for i in range(10)]
    path[5] = (0.3, 0.0, 0.2)  # a 30 cm glitch in one frame
    out = stream(seq, path)
    assert out[5] is None and seq.counters["dropped_jump"] == 1
    assert max(np.linalg.norm(o.position - np.array([0.005, 0, 0.2])) for o in out if o is not None) < 0.01


def test_a_real_fast_move_is_accepted_without_an_output_jump():
    seq = plain(jump_accept_after=3)
    path = [(0.0, 0, 0.2)] * 10 + [(0.2, 0, 0.2)] * 10  # the hand really is elsewhere now
    out = [o for o in stream(seq, path) if o is not None]
    steps = [np.linalg.norm(b.position - a.position) for a, b in zip(out, out[1:])]
    assert seq.counters["jumps_accepted"] == 1 and seq.counters["dropped_jump"] == 2
    assert max(steps) < 1e-9  # the output continues from where it was


def test_highest_priority_device_drives_and_switching_does_not_jump():
    seq = plain(device_priorities={"leap": 2, "spacemouse": 1}, device_timeout_s=0.05)
    t = 10.0
    outputs = []
    for _ in range(10):  # both devices publish; only the leap drives
        t += 0.01
        outputs.append(seq.process(sample(t, position=(0.1, 0, 0.2), device="leap"), now=t))
        assert seq.process(sample(t + 0.001, position=(0.5, 0, 0.2), device="spacemouse"), now=t + 0.001) is None
    assert seq.active_device == "leap" and seq.counters["dropped_inactive_device"] == 10
    for i in range(10):  # the leap goes quiet: the spacemouse takes over, from where the output was
        t += 0.01
        out = seq.process(sample(t, position=(0.5 + 0.001 * i, 0, 0.2), device="spacemouse"), now=t)
        if out is not None:
            outputs.append(out)
    assert seq.active_device == "spacemouse" and seq.counters["device_switches"] == 1
    steps = [np.linalg.norm(b.position - a.position) for a, b in zip(outputs, outputs[1:])]
    assert max(steps) < 0.002


def test_a_device_switch_keeps_the_orientation_and_later_turns_apply_from_there():
    # The second device sees the hand turned 90 degrees about z: the output must not turn
    # at the switch, and a later 10-degree turn of that device must turn the output by
    # exactly 10 degrees (the continuity offset is a rotation, applied on every frame).
    seq = plain(device_priorities={"leap": 2, "spacemouse": 1}, device_timeout_s=0.05)
    turned = Rotation.from_euler("z", 90, degrees=True)
    t, last = 10.0, None
    for _ in range(10):
        t += 0.01
        last = seq.process(sample(t, device="leap"), now=t)
    for _ in range(12):  # the leap is gone; the spacemouse takes over
        t += 0.01
        out = seq.process(sample(t, orientation=turned.as_quat(), device="spacemouse"), now=t)
        if out is not None:
            step = Rotation.from_quat(out.orientation).inv() * Rotation.from_quat(last.orientation)
            assert step.magnitude() < 1e-9
            last = out
    assert seq.counters["device_switches"] == 1
    more = Rotation.from_euler("z", 100, degrees=True).as_quat()
    for _ in range(12):  # the mean filter's window fills with the new orientation
        t += 0.01
        last = seq.process(sample(t, orientation=more, device="spacemouse"), now=t)
    angle = (Rotation.from_quat(last.orientation) * Rotation.from_quat(IDENTITY).inv()).magnitude()
    assert np.degrees(angle) == pytest.approx(10.0, abs=1e-6)
    assert np.linalg.norm(last.orientation) == pytest.approx(1.0)


def test_forced_device_and_frames_older_than_the_last_command():
    seq = plain(active_device="spacemouse")
    assert seq.process(sample(10.0, device="leap"), now=10.0) is None
    assert seq.process(sample(10.0, device="spacemouse"), now=10.0) is not None
    seq.note_command(10.05)
    assert seq.process(sample(10.04, device="spacemouse"), now=10.06) is None
    assert seq.counters["dropped_older_than_command"] == 1


@pytest.mark.parametrize("name", ["mean", "one_euro", "kalman"])
def test_every_filter_outputs_unit_quaternions_and_follows_a_ramp(name, rng):
    f = make_filter(name)
    base = Rotation.from_euler("z", 0.3)
    for i in range(200):
        noisy = (base * Rotation.from_rotvec(rng.normal(0, 0.01, 3))).as_quat()
        position, orientation = f.update(10.0 + 0.01 * i, np.array([0.002 * i, 0.0, 0.2]), noisy)
        assert np.linalg.norm(orientation) == pytest.approx(1.0)
        assert np.all(np.isfinite(position))
    assert abs(position[0] - 0.398) < 0.012  # following a 0.2 m/s ramp within ~6 frames of lag
    assert (Rotation.from_quat(orientation) * base.inv()).magnitude() < 0.02


def test_one_euro_rate_comes_from_stamps():
    """The same motion sampled at 50 and 200 Hz gives nearly the same output at the same
    instants; a filter that assumed a fixed 110 Hz rate would not."""

    def run(rate, assumed_rate=None):
        f = make_filter("one_euro")
        out = {}
        for k, t in enumerate(np.arange(0, 1.0, 1.0 / rate)):
            stamp = 10.0 + (k / assumed_rate if assumed_rate else t)
            p, _ = f.update(stamp, np.array([0.1 * np.sin(3 * t), 0.0, 0.2]), IDENTITY)
            out[round(t, 6)] = p[0]
        return out

    def gap(a, b):
        return max(abs(a[t] - b[t]) for t in a if t in b and t > 0.2)

    stamped = gap(run(50), run(200))
    fixed_rate = gap(run(50, assumed_rate=110), run(200, assumed_rate=110))
    assert stamped < 0.01 and stamped < fixed_rate / 2


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(-0.5, 0.5), st.floats(-0.5, 0.5), st.floats(0.0, 0.6), st.floats(0.001, 0.05)),
        min_size=1,
        max_size=60,
    ),
    st.sampled_from(["mean", "one_euro", "kalman"]),
)
def test_sequencer_output_is_always_finite_and_unit(steps, name):
    seq = Sequencer(SequencerConfig(filter_name=name, entry_trim_frames=2))
    t = 10.0
    for x, y, z, dt in steps:
        t += dt
        out = seq.process(sample(t, position=(x, y, z)), now=t)
        if out is not None:
            assert np.all(np.isfinite(out.position)) and np.linalg.norm(out.orientation) == pytest.approx(1.0)


def test_bad_gesture_fields_are_dropped_and_counted():
    from motion_sensor.sequencing.sequencer import validate_sample

    good = HandSample(
        stamp=1.0,
        position=np.zeros(3),
        orientation=np.array([0, 0, 0, 1.0]),
        grab_strength=0.5,
        pinch_strength=-1.0,
        index_tip=np.array([0.1, 0, 0]),
    )
    assert validate_sample(good) is None
    for field, value in [
        ("grab_strength", 1.5),
        ("pinch_strength", float("nan")),
        ("confidence", -0.5),
        ("index_tip", np.array([np.inf, 0, 0])),
    ]:
        bad = HandSample(stamp=1.0, position=np.zeros(3), orientation=np.array([0, 0, 0, 1.0]), **{field: value})
        assert validate_sample(bad) == "bad_hand_field", field


def test_sequencer_drops_non_numeric_fields_as_malformed():
    seq = plain()
    bad = sample(10.0)
    bad.orientation = ["a", 0, 0, 1]  # as a hand-built sample might carry
    assert seq.process(bad, now=10.0) is None and seq.counters["dropped_malformed"] == 1


def test_the_plain_float_gram_matrix_is_numpys():
    from motion_common.float_list import float_list
    from motion_sensor.sequencing.filters import _gram

    rng = np.random.default_rng(11)
    quats = rng.normal(size=(10, 4))
    np.testing.assert_allclose(_gram(quats.tolist()), quats.T @ quats, rtol=0, atol=1e-14)
    assert float_list(np.array([1, 2])) == [1.0, 2.0] and all(type(v) is float for v in float_list((1, 2.5)))
    with pytest.raises(ValueError):
        average_quaternions([])


def test_quaternion_mean_matches_the_exact_eigenvector_clustered_or_spread():
    # The power iteration must give Markley's mean (the exact principal eigenvector, as
    # numpy's eigh gives it) for the tight clusters of a real stream, and fall back to the
    # exact solver when the quaternions are spread so widely that it would not converge.
    rng = np.random.default_rng(3)
    for spread in (0.001, 0.05, 0.3, 3.0):
        for _ in range(50):
            base = rng.normal(size=4)
            quats = base / np.linalg.norm(base) + spread * rng.normal(size=(10, 4))
            quats /= np.linalg.norm(quats, axis=1)[:, None]
            quats[rng.random(10) < 0.3] *= -1  # q and -q are the same rotation
            _, vectors = np.linalg.eigh(quats.T @ quats)
            exact = vectors[:, -1] * np.sign(vectors[:, -1] @ quats[-1])
            np.testing.assert_allclose(average_quaternions(quats), exact, atol=1e-9)
    # Two opposite halves: no principal direction at all (equal eigenvalues) -> the exact
    # solver answers, and the answer is still a unit quaternion.
    pair = np.array([[0.0, 0.0, 0.0, 1.0]] * 5 + [[1.0, 0.0, 0.0, 0.0]] * 5)
    assert np.linalg.norm(average_quaternions(pair)) == pytest.approx(1.0)
